// weighted_friction: convolution-based unsteady friction, Zielke's laminar and Vardy & Brown's
// smooth-pipe turbulent weighting functions, evaluated recursively as sums of exponentials
// (model/effects/weighted_friction.h has the equations and the quadrature).
//
// As an effect: the momentum source S_i = (16 nu / D^2) sum_k y_k,i at every node of the pipe
// (u = (alpha + beta) / 2). Steady flow is untouched: no velocity change, no state, no
// source.
//
// Two interleaved grids. On the characteristic grid (dt = dx / c) the new point (i, n + 1) hangs
// on (i -+ 1, n), which hang on (i, n - 1): the even and the odd points of the space-time grid
// form two solutions that never meet. A node's velocity change over one step, u(n + 1) - u(n),
// takes one from each, and fed back through the convolution it couples them: on the swing after
// a valve closure that grew a step-to-step sawtooth at the fronts, whatever the sign of the
// source (the amplitude grew 18 % a period). So each parity of the time level has its own
// convolution, advanced every other step with u(n + 1) - u(n - 1) over 2 dt.
//
// The newest interval implicit. The source of step n + 1 is the convolution at n + 1,
// K (sum_k e_k y_k(n - 1) + g (u(n + 1) - u(n - 1))), e_k = exp(-n_k 2 dtau), g = sum_k of the
// newest interval's gains: S = a + b u_new with b = K g >= 0 (pipe_extension.h), first order in
// time. Explicit in the newest interval (the convolution up to n - 1 only), it was a damping one
// interval late: on the grid's shortest waves, which the scheme carries undamped at dt = dx / c,
// a late damping feeds them, and the swing after the closure grew 2 % a period at the fronts.
//
// The Reynolds number of Vardy & Brown's C*: `reynolds`, or with 0 the initial flow's,
// mean |u| D / nu over the pipe's nodes when the run starts. Below 2000 the flow is laminar and
// the laminar function is used whatever `weighting` says (Vardy & Brown's smooth-pipe function
// is a turbulent one; the NTNU rig starts at rest).
//
// Config example (Bergant & Simpson's rig, docs/bergant-simpson.md):
//   effect { name: "weighted_friction" param { key: "weighting" value: 1 } }
#include "model/effects/weighted_friction.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "model/common/status.h"
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

// Zeros of the Bessel function J_2: W's exact rates are their squares (Zielke 1968).
constexpr double kBesselJ2Zeros[] = {5.135622301840682,  8.417244140399864,  11.619841172149060,
                                     14.795951782351260, 17.959819494987823, 21.116997053021841,
                                     24.270112313573112, 27.420573549984557, 30.569204495516413,
                                     33.716519509222721};
constexpr int kExactTerms = 10;

// McMahon's expansion of the s-th zero of J_2 as a function of a continuous index x:
// j(beta) = beta - a1 / beta - a2 / beta^3, beta = (x + 3/4) pi, a1 = (mu - 1) / 8,
// a2 = 4 (mu - 1)(7 mu - 31) / (3 * 8^3), mu = 4 nu^2 = 16 (relative error 2e-7 at s = 11).
constexpr double kMcMahonA1 = 15.0 / 8.0;
constexpr double kMcMahonA2 = 4.0 * 15.0 * 81.0 / (3.0 * 512.0);

double McMahonZero(double beta) {
  return beta - kMcMahonA1 / beta - kMcMahonA2 / (beta * beta * beta);
}
double McMahonSlope(double beta) {  // dj / dbeta
  const double b2 = beta * beta;
  return 1.0 + kMcMahonA1 / b2 + 3.0 * kMcMahonA2 / (b2 * b2);
}
// beta of the zero j (Newton; j is increasing and nearly the identity).
double McMahonBeta(double j) {
  double beta = j + kMcMahonA1 / j;
  for (int i = 0; i < 8; ++i) beta -= (McMahonZero(beta) - j) / McMahonSlope(beta);
  return beta;
}
// dx / dlambda = 1 / (2 j pi dj/dbeta): the density of the rates.
double RateDensity(double lambda) {
  const double j = std::sqrt(lambda);
  return 1.0 / (2.0 * j * M_PI * McMahonSlope(McMahonBeta(j)));
}

// The quadrature of F(tau) = integral_0^inf rho(s) exp(-(shift + s) tau) ds: s = e^sigma and the
// midpoint rule in sigma, nodes sigma_lo + (k + 1/2) h, k = 0..nodes-1, h = (sigma_hi -
// sigma_lo) / nodes. On the whole line this rule's error falls as exp(-pi^2 / h) (Poisson
// summation; the integrand is analytic in the strip |Im sigma| < pi / 2); cut at sigma_lo it would
// be off by h^2 / 24 of the integrand's slope there (Euler-Maclaurin). So the nodes below
// sigma_lo stay, lumped into one exponential with their mass and mean rate: they all have
// e^sigma tau < e^sigma_lo tau, where exp(-s tau) is nearly linear in s. Appends to *sum.
template <typename Density>
void AppendLaplaceQuadrature(const Density& density, double shift, double sigma_lo, double sigma_hi,
                             int nodes, ExponentialSum* sum) {
  const double h = (sigma_hi - sigma_lo) / nodes;
  double mass = 0.0, moment = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double s = std::exp(sigma_lo - (k + 0.5) * h);
    const double weight = h * s * density(s);
    mass += weight;
    moment += weight * s;
    if (weight < 1e-17 * mass) break;
  }
  sum->weights.push_back(mass);
  sum->rates.push_back(shift + moment / mass);
  for (int k = 0; k < nodes; ++k) {
    const double s = std::exp(sigma_lo + (k + 0.5) * h);
    sum->weights.push_back(h * s * density(s));
    sum->rates.push_back(shift + s);
  }
}

// The highest quadrature rate: W is carried down to tau = 1e-4 dtau, so the newest step's
// integral of W is short by 1 / sqrt(pi 1e4) = 0.6 % of its own share (the tail
// integral_0^dtau tau^(-1/2) Gamma(1/2, s_max tau) dtau = 2 / sqrt(s_max)).
double HighestRate(double dtau) { return 1e4 / dtau; }

// The lowest quadrature node at least four e-folds below the highest.
double LowerLimit(double sigma_lo, double sigma_hi) { return std::min(sigma_lo, sigma_hi - 4.0); }

}  // namespace

double ExponentialSum::operator()(double tau) const {
  double w = 0.0;
  for (std::size_t k = 0; k < weights.size(); ++k) w += weights[k] * std::exp(-rates[k] * tau);
  return w;
}

double ZielkeWeighting(double tau) {
  if (tau <= 0.02) {
    constexpr double m[] = {0.282095, -1.25, 1.057855, 0.9375, 0.396696, -0.351563};
    double w = 0.0;
    for (int j = 0; j < 6; ++j) w += m[j] * std::pow(tau, 0.5 * (j - 1));
    return w;
  }
  constexpr double n[] = {26.3744, 70.8493, 135.0198, 218.9216, 322.5544};
  double w = 0.0;
  for (double rate : n) w += std::exp(-rate * tau);
  return w;
}

double VardyBrownDecayCoefficient(double reynolds) {
  const double kappa = std::log10(15.29 / std::pow(reynolds, 0.0567));
  return 12.86 / std::pow(reynolds, kappa);
}

double VardyBrownWeighting(double tau, double reynolds) {
  const double a_star = 0.5 / std::sqrt(M_PI);
  return a_star * std::exp(-tau / VardyBrownDecayCoefficient(reynolds)) / std::sqrt(tau);
}

// sum_{i <= 10} exp(-j_i^2 tau) exactly, then sum_{i > 10} exp(-lambda_i tau) by Euler-Maclaurin
// about the midpoints, integral_{10.5}^inf f(x) dx + f'(10.5) / 24 with f = exp(-lambda(x) tau):
// the integral is integral_0^inf rho(s) exp(-(L0 + s) tau) ds with L0 = lambda(10.5) and
// rho = dx/dlambda (McMahon), by the quadrature; the correction, -(lambda'(10.5) / 24) tau
// exp(-L0 tau), up to 4e-4 of W at tau ~ 1 / L0, as the difference quotient of two exponentials
// at L0 -+ d, d = L0 / 10 (off by (d tau)^2 / 6 of itself). The next term, 7 f''' / 5760, is below
// 1e-6 of W. The quadrature's nodes from s = L0 / 20 up; those below, whose rates are within 5 %
// of L0, lumped.
ExponentialSum ZielkeExponentials(double dtau, int terms) {
  MPDRIG_CHECK(dtau > 0.0 && terms >= kExactTerms + 5);
  ExponentialSum sum;
  for (double j : kBesselJ2Zeros) {
    sum.weights.push_back(1.0);
    sum.rates.push_back(j * j);
  }
  const double x0 = kExactTerms + 0.5;
  const double beta0 = (x0 + 0.75) * M_PI;
  const double j0 = McMahonZero(beta0);
  const double lambda0 = j0 * j0;
  const double slope = 2.0 * j0 * M_PI * McMahonSlope(beta0);  // dlambda/dx at x0
  const double d = 0.1 * lambda0;
  sum.weights.push_back(-slope / (24.0 * 2.0 * d));
  sum.rates.push_back(lambda0 - d);
  sum.weights.push_back(slope / (24.0 * 2.0 * d));
  sum.rates.push_back(lambda0 + d);
  const double sigma_hi = std::log(HighestRate(dtau));
  const double sigma_lo = LowerLimit(std::log(lambda0 / 20.0), sigma_hi);
  AppendLaplaceQuadrature([&](double s) { return RateDensity(lambda0 + s); }, lambda0, sigma_lo,
                          sigma_hi, terms - kExactTerms - 3, &sum);
  return sum;
}

// A* exp(-tau / C*) tau^(-1/2) = (A* / sqrt(pi)) integral_0^inf s^(-1/2) exp(-(1/C* + s) tau) ds.
// The nodes from 1.5e-3 / C* up: the lumped ones below have s tau < 0.015 up to tau = 10 C*, where
// W has fallen by e^-10.
ExponentialSum VardyBrownExponentials(double reynolds, double dtau, int terms) {
  MPDRIG_CHECK(dtau > 0.0 && terms >= 3 && reynolds > 0.0);
  const double c_star = VardyBrownDecayCoefficient(reynolds);
  const double scale = 0.5 / M_PI;  // A* / sqrt(pi)
  const double sigma_hi = std::log(HighestRate(dtau));
  const double sigma_lo = LowerLimit(std::log(1.5e-3 / c_star), sigma_hi);
  ExponentialSum sum;
  AppendLaplaceQuadrature([&](double s) { return scale / std::sqrt(s); }, 1.0 / c_star, sigma_lo,
                          sigma_hi, terms - 1, &sum);
  return sum;
}

WeightingConvolution::WeightingConvolution(const ExponentialSum& weighting, double dtau,
                                           int points) {
  MPDRIG_CHECK(dtau > 0.0 && points > 0 && weighting.rates.size() == weighting.weights.size());
  for (std::size_t k = 0; k < weighting.rates.size(); ++k) {
    const double x = weighting.rates[k] * dtau;
    decay_.push_back(std::exp(-x));
    gain_.push_back(weighting.weights[k] * (x > 0.0 ? -std::expm1(-x) / x : 1.0));
    newest_gain_ += gain_.back();
  }
  states_.assign(static_cast<std::size_t>(points) * decay_.size(), 0.0);
}

void WeightingConvolution::Reset() { std::fill(states_.begin(), states_.end(), 0.0); }

void WeightingConvolution::Advance(std::span<const double> velocity_change) {
  const std::size_t terms = decay_.size();
  MPDRIG_CHECK(velocity_change.size() * terms == states_.size());
  for (std::size_t i = 0; i < velocity_change.size(); ++i) {
    double* y = &states_[i * terms];
    const double dv = velocity_change[i];
    for (std::size_t k = 0; k < terms; ++k) y[k] = decay_[k] * y[k] + gain_[k] * dv;
  }
}

double WeightingConvolution::Decayed(int point) const {
  const std::size_t terms = decay_.size();
  const double* y = &states_[static_cast<std::size_t>(point) * terms];
  double sum = 0.0;
  for (std::size_t k = 0; k < terms; ++k) sum += decay_[k] * y[k];
  return sum;
}

double WeightingConvolution::Value(int point) const {
  const std::size_t terms = decay_.size();
  const double* y = &states_[static_cast<std::size_t>(point) * terms];
  double sum = 0.0;
  for (std::size_t k = 0; k < terms; ++k) sum += y[k];
  return sum;
}

namespace {

// Below this Reynolds number the flow is laminar: Zielke's function.
constexpr double kLaminarReynolds = 2000.0;

class WeightedFriction final : public Effect {
 public:
  WeightedFriction(const PipeConfig& pipe, double dt_s, bool turbulent, double viscosity_m2ps,
                   double reynolds, int terms)
      : diameter_m_(std::sqrt(4.0 * pipe.area_m2 / M_PI)),
        viscosity_m2ps_(viscosity_m2ps),
        dtau_(8.0 * viscosity_m2ps * dt_s / (diameter_m_ * diameter_m_)),
        turbulent_(turbulent),
        reynolds_(reynolds),
        terms_(terms),
        gain_per_s_(16.0 * viscosity_m2ps / (diameter_m_ * diameter_m_)) {}

  void Initialize(const PipeSolver& pipe, const ChannelValues& /*channels*/) override {
    const std::vector<double>& alpha = pipe.alpha();
    const std::vector<double>& beta = pipe.beta();
    const std::size_t nodes = alpha.size();
    double mean_speed = 0.0;
    for (int parity = 0; parity < 2; ++parity) velocity_[parity].resize(nodes);
    for (std::size_t i = 0; i < nodes; ++i) {
      const double u = 0.5 * (alpha[i] + beta[i]);
      velocity_[0][i] = velocity_[1][i] = u;
      mean_speed += std::fabs(u) / static_cast<double>(nodes);
    }
    const double reynolds =
        reynolds_ > 0.0 ? reynolds_ : mean_speed * diameter_m_ / viscosity_m2ps_;
    const ExponentialSum weighting = turbulent_ && reynolds >= kLaminarReynolds
                                         ? VardyBrownExponentials(reynolds, dtau_, terms_)
                                         : ZielkeExponentials(dtau_, terms_);
    for (int parity = 0; parity < 2; ++parity) {
      convolution_[parity].emplace(weighting, dtau_, static_cast<int>(nodes));
    }
    change_.assign(nodes, 0.0);
    steps_ = 0;
  }

  bool adds_momentum_source() const override { return true; }
  // Step n + 1: the convolution of its parity at n + 1, with the newest interval's change
  // u(n + 1) - u(n - 1) implicit: S = K (Decayed + g (u_new - u(n - 1))), K = 16 nu / D^2,
  // g = newest_gain.
  void AddMomentumSource(const PipeSnapshot& /*state*/, std::span<double> explicit_mps2,
                         std::span<double> implicit_per_s) const override {
    const int parity = static_cast<int>((steps_ + 1) % 2);
    const auto& convolution = convolution_[parity];
    if (!convolution) return;  // not started
    const std::vector<double>& before = velocity_[parity];
    const double b = gain_per_s_ * convolution->newest_gain();
    for (std::size_t i = 0; i < explicit_mps2.size(); ++i) {
      explicit_mps2[i] += gain_per_s_ * convolution->Decayed(static_cast<int>(i)) - b * before[i];
      implicit_per_s[i] += b;
    }
  }

  // After step n + 1: u(n + 1) - u(n - 1) into the convolution of its parity.
  void AfterStep(const PipeSolver& pipe, const StepRecord& /*step*/) override {
    ++steps_;
    auto& convolution = convolution_[steps_ % 2];
    if (!convolution) return;
    std::vector<double>& velocity = velocity_[steps_ % 2];
    const std::vector<double>& alpha = pipe.alpha();
    const std::vector<double>& beta = pipe.beta();
    for (std::size_t i = 0; i < velocity.size(); ++i) {
      const double u = 0.5 * (alpha[i] + beta[i]);
      change_[i] = u - velocity[i];
      velocity[i] = u;
    }
    convolution->Advance(change_);
  }

 private:
  double diameter_m_;
  double viscosity_m2ps_;
  double dtau_;  // of two steps
  bool turbulent_;
  double reynolds_;
  int terms_;
  double gain_per_s_;  // 16 nu / D^2
  // The even and the odd time levels: each its own convolution, advanced every other step.
  std::optional<WeightingConvolution> convolution_[2];
  std::vector<double> velocity_[2];  // u_i at the last level of that parity
  std::vector<double> change_;
  long steps_ = 0;
};

}  // namespace

const EffectInfo& WeightedFrictionEffect() {
  static const EffectInfo info{
      "weighted_friction",
      "convolution unsteady friction S = (16 nu / D^2) integral W(t - s) du/ds ds: Zielke's "
      "laminar or Vardy & Brown's smooth-pipe weighting function, as a sum of exponentials",
      "beyond the thesis (its 8.6.12 is the instantaneous-acceleration model): Zielke 1968, "
      "Vardy & Brown 2003, Vitkovsky et al. 2004",
      "damps a water hammer's later swings and shortens the cavities after the first, with the "
      "wall shear of a flow's own history; for valve-closure rigs, not a diagnose candidate",
      {{"weighting", "-",
        "0: Zielke's laminar function; 1: Vardy & Brown's smooth-pipe turbulent function (the "
        "laminar one where Re < 2000); values round to the nearer",
        1.0, 0.0, 1.0, false},
       {"kinematic_viscosity_m2ps", "m^2/s", "kinematic viscosity nu (water at 15 degC: 1.14e-6)",
        1.14e-6, 1.0e-7, 1.0e-3, false},
       {"reynolds", "-",
        "Reynolds number of Vardy & Brown's C* = 12.86 / Re^kappa; 0: the initial flow's, mean "
        "|u| D / nu over the pipe",
        0.0, 0.0, 1.0e8, false},
       {"terms", "-",
        "exponentials per node (Zielke's: ten exact, the rest by quadrature); the error of W "
        "falls as exp(-pi^2 / h), h the quadrature's step (32: Zielke's within 1.2e-4, Vardy & "
        "Brown's 6e-6); rounded",
        32.0, 24.0, 200.0, false}},
      [](const EffectContext& context) {
        return std::make_unique<WeightedFriction>(
            context.pipe, context.dt_s, context.Get("weighting") >= 0.5,
            context.Get("kinematic_viscosity_m2ps"), context.Get("reynolds"),
            static_cast<int>(std::lround(context.Get("terms"))));
      },
      /*diagnose_candidate=*/false};
  return info;
}

}  // namespace mpdrig
