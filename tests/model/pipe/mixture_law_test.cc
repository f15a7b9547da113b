// The mixture law's inverse (MixtureLaw::Pressure, model/pipe/mixture_law.h): its pressure is the
// exact inverse of the tabulated W to within round-off, whatever the guess it starts from. The
// reference is bisection of W itself to the last bit (what the earlier Newton iteration, run to
// 1e-15 in ln p, computed too), for entrained gas as gas_entrainment models it (thesis 8.3.5,
// 8.3.6) and for the liquid alone, both pipe models.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "model/params/rig_params.h"
#include "model/pipe/mixture_law.h"

namespace mpdrig {
namespace {

// gas_entrainment's extra compressibility: eps(p) / (n p) - eps(p) / K, eps = eps0 p_ref / p.
MixtureLaw Mixture(PipeModel model, double eps0) {
  const RigParams params;
  const double c = params.wave_speed_mps;
  const double rho = params.density_kgpm3;
  const PipeLaw law(model, c, rho, params.QuasiLinearK(), 4e5);
  const double bulk = rho * c * c;
  return MixtureLaw(law, rho, params.QuasiLinearK(), [eps0, bulk](double p) {
    const double eps = eps0 * 101325.0 / std::max(p, 1e-300);
    return std::max(0.0, eps / p - eps / bulk);
  });
}

// The pressure whose W is w, by bisection of ln p to adjacent doubles.
double BisectedPressure(const MixtureLaw& mixture, double w) {
  double lo = std::log(1.0), hi = std::log(1e9);
  while (true) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (mixture.W(std::exp(mid)) < w ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

TEST(MixtureLaw, InverseIsTheTablesToRoundOffFromAnyGuess) {
  for (PipeModel model : {PipeModel::kQuasiLinear, PipeModel::kLinear}) {
    for (double eps0 : {0.0, 1e-4, 1e-3}) {
      const MixtureLaw mixture = Mixture(model, eps0);
      std::mt19937 random(7);
      // The rig's range and beyond: 1 kPa (column separation) to 100 bar, log-uniform.
      std::uniform_real_distribution<double> log_pressure(std::log(1e3), std::log(1e7));
      std::uniform_real_distribution<double> nearby(-0.003, 0.003);  // about one table interval
      double largest = 0.0;
      for (int k = 0; k < 2000; ++k) {
        const double p = std::exp(log_pressure(random));
        const double w = mixture.W(p);
        const double reference = BisectedPressure(mixture, w);
        // What the last bits leave undetermined in ln p: 8 units of round-off of w over
        // dW/d(ln p) (1e-13 for the liquid alone at 1 kPa, where W is flat in ln p), and of
        // ln p itself (4e-15 at 1 bar).
        const double epsilon = std::numeric_limits<double>::epsilon();
        const double resolution =
            8.0 * epsilon * std::max(std::fabs(w), 1.0) / (reference * mixture.DW(reference)) +
            8.0 * epsilon * std::fabs(std::log(reference));
        // A solver's guess: the node's last pressure (nearby), a wrong one, none.
        for (double guess : {p * std::exp(nearby(random)), p * 3.0, 0.0}) {
          const double inverse = mixture.Pressure(w, guess);
          largest = std::max(largest, std::fabs(inverse / reference - 1.0) / resolution);
        }
      }
      std::printf("eps0 %g: largest error %.3g resolutions\n", eps0, largest);
      // Within W's own round-off: the relative pressure error in units of that resolution.
      EXPECT_LT(largest, 1.0) << "eps0 " << eps0;
    }
  }
}

}  // namespace
}  // namespace mpdrig
