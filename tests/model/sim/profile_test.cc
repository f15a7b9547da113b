#include "model/sim/profile.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

// Profiles are closed forms evaluated in double precision: 1e-12 absolute on values of order 1.
constexpr double kValueTol = 1e-12;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::unique_ptr<Profile> ParseOk(const std::string& spec, const std::string& unit = "m",
                                 double default_duration_s = 10.0) {
  auto profile = ParseProfile(spec, unit, default_duration_s);
  EXPECT_TRUE(profile.ok()) << spec << ": " << profile.status().message();
  return profile.ok() ? std::move(profile).value() : nullptr;
}

std::string ErrorOf(const std::string& spec, const std::string& unit = "m") {
  auto profile = ParseProfile(spec, unit, 10.0);
  EXPECT_FALSE(profile.ok()) << "accepted " << spec;
  return profile.ok() ? std::string() : profile.status().message();
}

TEST(Profile, Constant) {
  auto profile = ParseOk("31.5", "deg");
  ASSERT_NE(profile, nullptr);
  for (double t : {-1.0, 0.0, 3.7, 1e4}) EXPECT_EQ(profile->ValueAt(t), 31.5);
  EXPECT_FALSE(profile->Describe().empty());
  auto negative = ParseOk("-0.25");
  ASSERT_NE(negative, nullptr);
  EXPECT_EQ(negative->ValueAt(1.0), -0.25);
}

TEST(Profile, Sine) {
  auto profile = ParseOk("sine:amp_m=0.1,freq_hz=0.2");
  ASSERT_NE(profile, nullptr);
  for (double t = 0.0; t < 10.0; t += 0.37) {
    EXPECT_NEAR(profile->ValueAt(t), 0.1 * std::sin(kTwoPi * 0.2 * t), kValueTol) << t;
  }
  EXPECT_NEAR(profile->ValueAt(1.25), 0.1, kValueTol);  // a quarter period: the crest
}

TEST(Profile, SineWithMeanAndPhase) {
  auto profile = ParseOk("sine:mean_deg=31,amp_deg=5,freq_hz=0.5,phase_deg=90", "deg");
  ASSERT_NE(profile, nullptr);
  for (double t = 0.0; t < 4.0; t += 0.13) {
    EXPECT_NEAR(profile->ValueAt(t), 31.0 + 5.0 * std::cos(kTwoPi * 0.5 * t), 1e-11) << t;
  }
}

// Times in [t_begin, t_end] where `f` changes sign, refined by bisection to 1e-13 s.
std::vector<double> ZeroCrossings(const std::function<double(double)>& f, double t_begin,
                                  double t_end, double scan_step) {
  std::vector<double> crossings;
  double a = t_begin;
  double fa = f(a);
  for (double b = t_begin + scan_step; b <= t_end + 1e-12; b += scan_step) {
    const double fb = f(b);
    if ((fa < 0.0) != (fb < 0.0)) {
      double lo = a, hi = b;
      while (hi - lo > 1e-13) {
        const double mid = 0.5 * (lo + hi);
        if ((f(mid) < 0.0) == (fa < 0.0))
          lo = mid;
        else
          hi = mid;
      }
      crossings.push_back(0.5 * (lo + hi));
    }
    a = b;
    fa = fb;
  }
  return crossings;
}

// Linear chirp: phase 2 pi (f0 t + (f1 - f0) t^2 / (2 T)), so the instantaneous frequency is
// f0 + (f1 - f0) t / T. Between two zero crossings the phase advances by pi, so 1 / (2 dt) is
// the mean frequency over the half period, which for a linear law is the frequency at the
// midpoint, exactly. Bisection to 1e-13 s on half periods >= 0.25 s bounds the estimate's
// error far below the 1e-9 Hz tolerance.
TEST(Profile, SweepFrequencyRisesLinearlyFromF0ToF1) {
  const double f0 = 0.5, f1 = 2.0, duration = 8.0;
  auto profile = ParseOk("sweep:amp_m=0.01,f0_hz=0.5,f1_hz=2,duration_s=8");
  ASSERT_NE(profile, nullptr);
  EXPECT_NEAR(profile->ValueAt(0.0), 0.0, kValueTol);
  auto value = [&](double t) { return profile->ValueAt(t); };
  // t = 0 is a crossing (the phase starts at 0); scan from just after it.
  const std::vector<double> crossings = ZeroCrossings(value, 0.05, duration + 3.0, 0.01);
  ASSERT_GT(crossings.size(), 20u);
  auto instantaneous = [&](double t) { return t <= duration ? f0 + (f1 - f0) * t / duration : f1; };
  // Least-squares line through (midpoint, estimate) of the half periods inside the sweep: it
  // must start at f0 and end at f1.
  double sum_t = 0.0, sum_f = 0.0, sum_tt = 0.0, sum_tf = 0.0;
  int in_sweep = 0, after_end = 0;
  double previous = 0.0;
  for (double crossing : crossings) {
    const double estimate = 0.5 / (crossing - previous);
    const double midpoint = 0.5 * (crossing + previous);
    if (crossing <= duration) {
      EXPECT_NEAR(estimate, instantaneous(midpoint), 1e-9) << "half period ending at " << crossing;
      sum_t += midpoint;
      sum_f += estimate;
      sum_tt += midpoint * midpoint;
      sum_tf += midpoint * estimate;
      ++in_sweep;
    } else if (previous >= duration) {
      EXPECT_NEAR(estimate, f1, 1e-9) << "after the sweep, at " << crossing;
      ++after_end;
    }
    previous = crossing;
  }
  ASSERT_GT(in_sweep, 10);
  EXPECT_GT(after_end, 5);
  const double slope = (in_sweep * sum_tf - sum_t * sum_f) / (in_sweep * sum_tt - sum_t * sum_t);
  const double intercept = (sum_f - slope * sum_t) / in_sweep;
  EXPECT_NEAR(intercept, f0, 1e-8);
  EXPECT_NEAR(intercept + slope * duration, f1, 1e-8);
  // And the phase formula itself, at the end of the sweep.
  const double phase_end = kTwoPi * (f0 * duration + 0.5 * (f1 - f0) * duration);
  EXPECT_NEAR(profile->ValueAt(duration), 0.01 * std::sin(phase_end), kValueTol);
}

TEST(Profile, SweepUsesTheDefaultDurationAndMean) {
  auto profile = ParseProfile("sweep:amp_deg=2,f0_hz=0.1,f1_hz=0.3,mean_deg=31", "deg", 20.0);
  ASSERT_TRUE(profile.ok()) << profile.status().message();
  const double t = 13.0;
  const double phase = kTwoPi * (0.1 * t + 0.5 * 0.2 * t * t / 20.0);
  EXPECT_NEAR((*profile)->ValueAt(t), 31.0 + 2.0 * std::sin(phase), 1e-11);
  EXPECT_NEAR((*profile)->ValueAt(0.0), 31.0, kValueTol);
}

TEST(Profile, StepWithoutRise) {
  auto profile = ParseOk("step:amp_m=0.2,t_s=1.5");
  ASSERT_NE(profile, nullptr);
  EXPECT_EQ(profile->ValueAt(0.0), 0.0);
  EXPECT_EQ(profile->ValueAt(1.5), 0.0);
  EXPECT_EQ(profile->ValueAt(1.5 + 1e-9), 0.2);
  EXPECT_EQ(profile->ValueAt(100.0), 0.2);
}

TEST(Profile, StepWithRise) {
  auto profile = ParseOk("step:amp_deg=-10,t_s=2,rise_s=0.5,mean_deg=40", "deg");
  ASSERT_NE(profile, nullptr);
  EXPECT_EQ(profile->ValueAt(1.0), 40.0);
  EXPECT_EQ(profile->ValueAt(2.0), 40.0);
  EXPECT_NEAR(profile->ValueAt(2.125), 37.5, kValueTol * 40.0);
  EXPECT_NEAR(profile->ValueAt(2.25), 35.0, kValueTol * 40.0);
  EXPECT_NEAR(profile->ValueAt(2.5), 30.0, kValueTol * 40.0);
  EXPECT_EQ(profile->ValueAt(10.0), 30.0);
}

TEST(Profile, UnknownKindListsTheValidOnes) {
  const std::string message = ErrorOf("square:amp_m=0.1,freq_hz=0.2");
  EXPECT_NE(message.find("'square'"), std::string::npos) << message;
  for (const char* kind : {"sine", "sweep", "step"}) {
    EXPECT_NE(message.find(kind), std::string::npos) << message;
  }
}

TEST(Profile, UnknownKeyListsTheAcceptedOnes) {
  const std::string message = ErrorOf("sine:amp_m=0.1,freq_hz=0.2,offset_m=1");
  EXPECT_NE(message.find("'offset_m'"), std::string::npos) << message;
  for (const char* key : {"amp_m", "freq_hz", "mean_m", "phase_deg"}) {
    EXPECT_NE(message.find(key), std::string::npos) << message;
  }
}

TEST(Profile, MissingKey) {
  const std::string message = ErrorOf("sine:amp_m=0.1");
  EXPECT_NE(message.find("missing"), std::string::npos) << message;
  EXPECT_NE(message.find("freq_hz"), std::string::npos) << message;
  EXPECT_NE(ErrorOf("sweep:amp_m=0.1,f0_hz=0.1").find("f1_hz"), std::string::npos);
  EXPECT_NE(ErrorOf("step:amp_m=0.1").find("t_s"), std::string::npos);
  EXPECT_NE(ErrorOf("sine:").find("missing"), std::string::npos);
}

TEST(Profile, DuplicateKey) {
  const std::string message = ErrorOf("sine:amp_m=0.1,freq_hz=0.2,amp_m=0.2");
  EXPECT_NE(message.find("amp_m"), std::string::npos) << message;
  EXPECT_NE(message.find("twice"), std::string::npos) << message;
}

TEST(Profile, NonNumbers) {
  for (const char* spec : {"sine:amp_m=abc,freq_hz=0.2", "sine:amp_m=,freq_hz=0.2",
                           "sine:amp_m=nan,freq_hz=0.2", "sine:amp_m=inf,freq_hz=0.2",
                           "sine:amp_m=0.1x,freq_hz=0.2", "sine:amp_m= 0.1,freq_hz=0.2"}) {
    const std::string message = ErrorOf(spec);
    EXPECT_NE(message.find("amp_m"), std::string::npos) << spec << ": " << message;
  }
  EXPECT_FALSE(ErrorOf("sine:amp_m,freq_hz=0.2").empty());  // not key=value
  EXPECT_FALSE(ErrorOf("abc").empty());
  EXPECT_FALSE(ErrorOf("").empty());
  EXPECT_FALSE(ErrorOf("nan").empty());
}

TEST(Profile, WrongUnitSuffix) {
  // A piston amplitude given to the choke, which takes degrees.
  const std::string message = ErrorOf("sine:amp_m=0.1,freq_hz=0.2", "deg");
  EXPECT_NE(message.find("'amp_m'"), std::string::npos) << message;
  EXPECT_NE(message.find("amp_deg"), std::string::npos) << message;
  EXPECT_FALSE(ErrorOf("step:amp_deg=10,t_s=1", "m").empty());
}

TEST(Profile, OutOfRangeSettings) {
  EXPECT_FALSE(ErrorOf("sine:amp_m=0.1,freq_hz=-0.2").empty());
  EXPECT_FALSE(ErrorOf("sweep:amp_m=0.1,f0_hz=0.1,f1_hz=1,duration_s=0").empty());
  EXPECT_FALSE(ErrorOf("sweep:amp_m=0.1,f0_hz=-0.1,f1_hz=1").empty());
  EXPECT_FALSE(ErrorOf("step:amp_m=0.1,t_s=1,rise_s=-1").empty());
  EXPECT_FALSE(ParseProfile("sweep:amp_m=0.1,f0_hz=0.1,f1_hz=1", "m", 0.0).ok());
}

}  // namespace
}  // namespace mpdrig
