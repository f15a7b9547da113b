// Disturbance model, pole placement and the output-injection gains (10.1.16)-(10.1.17).
#include "model/observer/observer_gains.h"

#include <cmath>
#include <complex>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

namespace mpdrig::observer {
namespace {

TEST(DisturbanceModelTest, PlacesRequestedPoles) {
  const RigParams params;
  for (double hz : {0.1, 0.25, 0.3}) {
    for (std::complex<double> pole : {std::complex<double>(-40, 20), {-4, 2}, {-3, 0}}) {
      auto d = SinusoidDisturbance::Create(hz, params.PistonDisplacementAreaM2(), pole);
      ASSERT_TRUE(d.ok()) << d.status().message();
      const Eigen::Matrix2d closed = d->a - d->l * d->c;
      // Characteristic polynomial s^2 - tr s + det must be (s - p)(s - conj p): compare the
      // coefficients (robust also for the double real pole, where eigenvalues are ill-conditioned).
      EXPECT_NEAR(closed.trace(), 2 * pole.real(), 1e-9 * std::abs(pole));
      EXPECT_NEAR(closed.determinant(), std::norm(pole), 1e-9 * std::norm(pole));
      if (pole.imag() != 0.0) {
        Eigen::EigenSolver<Eigen::Matrix2d> eig(closed);
        const double im = std::fabs(eig.eigenvalues()(0).imag());
        EXPECT_NEAR(eig.eigenvalues()(0).real(), pole.real(), 1e-9 * std::abs(pole));
        EXPECT_NEAR(im, std::fabs(pole.imag()), 1e-9 * std::abs(pole));
      }
      // exp(A t) is the rotation solving dX/dt = A X.
      const double t = 0.37;
      Eigen::Matrix2d numeric = Eigen::Matrix2d::Identity(), term = numeric;
      for (int k = 1; k < 40; ++k) {
        term = term * d->a * t / k;
        numeric += term;
      }
      EXPECT_LT((numeric - d->Exp(t)).norm(), 1e-12);
    }
  }
}

TEST(DisturbanceModelTest, RejectsBadInput) {
  EXPECT_FALSE(SinusoidDisturbance::Create(0.0, 1e-4, {-40, 20}).ok());
  EXPECT_FALSE(SinusoidDisturbance::Create(0.2, 1e-4, {1, 20}).ok());
  EXPECT_FALSE(SinusoidDisturbance::Create(std::nan(""), 1e-4, {-40, 20}).ok());
}

// Thesis 10.3: "p2(x) ~ 0 and p1(x) ~ C exp(A h(x)) L" for small friction. With the defaults
// (sigma = 0.079) the kernel terms are O(sigma) of the gains: p2 / max|p1| and the relative kernel
// correction of p1 are below 10 %, and both vanish without friction. They scale with sigma: at a
// tenth of f1 the relative size drops about tenfold.
TEST(ObserverGainsTest, KernelCorrectionIsSmallForSmallFriction) {
  RigParams params;
  ObserverOptions options;
  options.disturbance_hz = 0.25;
  options.cells = 100;
  auto relative_sizes = [&](double f1) {
    options.friction_f1_per_s = f1;
    auto g = ObserverGains::Compute(params, options);
    EXPECT_TRUE(g.ok()) << g.status().message();
    double p1_max = 0.0, p2_max = 0.0, diff_max = 0.0;
    for (std::size_t i = 0; i < g->p1.size(); ++i) {
      p1_max = std::max(p1_max, std::fabs(g->p1[i]));
      p2_max = std::max(p2_max, std::fabs(g->p2[i]));
      diff_max = std::max(diff_max, std::fabs(g->p1[i] - g->p1_without_kernel[i]));
    }
    return std::make_pair(p2_max / p1_max, diff_max / p1_max);
  };
  const auto [p2_none, diff_none] = relative_sizes(0.0);
  EXPECT_EQ(p2_none, 0.0);
  EXPECT_EQ(diff_none, 0.0);
  const auto [p2_thesis, diff_thesis] = relative_sizes(0.15);
  EXPECT_GT(p2_thesis, 1e-4);
  EXPECT_LT(p2_thesis, 0.1);
  EXPECT_LT(diff_thesis, 0.1);
  const auto [p2_small, diff_small] = relative_sizes(0.015);
  EXPECT_LT(p2_small, 0.15 * p2_thesis);
  EXPECT_LT(diff_small, 0.15 * diff_thesis);
}

// p1 at the outlet is C L (h(1) = 0, the integral vanishes) minus epsilon P^uu(1, 1).
TEST(ObserverGainsTest, OutletGainClosedForm) {
  const RigParams params;
  ObserverOptions options;
  options.cells = 50;
  auto g = ObserverGains::Compute(params, options);
  ASSERT_TRUE(g.ok()) << g.status().message();
  const double sigma = g->coordinates.sigma;
  const double cl = g->disturbance.c * g->disturbance.l;
  EXPECT_NEAR(cl, 80.0, 1e-9);  // C L = -trace(A - L C) = -2 Re(pole): A is traceless
  EXPECT_NEAR(g->p1.back(), cl + g->coordinates.epsilon_per_s * 0.5 * sigma * (1 + sigma), 1e-9);
  EXPECT_NEAR(g->p2.back(), -g->coordinates.epsilon_per_s * 0.5 * sigma * std::exp(-2 * sigma),
              1e-12);
}

// The change of coordinates (10.2.1)-(10.2.2) and its inverse, and the relation (10.2.24)-(10.2.25)
// to the simulator's linear Riemann invariants (7.0.6)-(7.0.7), alpha = P/(rho c) + q/A and
// beta = -P/(rho c) + q/A with the gravity-free P: alpha = (2/A) e^{-sigma x} u,
// beta = (2/A) e^{sigma x} v. The corrective terms (10.2.26)-(10.2.27) follow by linearity.
TEST(ObserverCoordinatesTest, RoundTripAndSimulatorInvariants) {
  const RigParams params;
  const ObserverCoordinates co = ObserverCoordinates::Create(params, params.friction_f1_per_s);
  const double p_sp = 5.1e5;
  const double rho_c = params.density_kgpm3 * params.wave_speed_mps;
  const double area = params.PipeAreaM2();
  for (double x : {0.0, 0.3, 1.0}) {
    for (double p : {2.0e5, 5.0e5, 9.0e5}) {
      for (double q : {-2e-5, 0.0, 3e-5}) {
        const double u = co.UpWave(x, p, q, p_sp);
        const double v = co.DownWave(x, p, q, p_sp);
        EXPECT_NEAR(co.Pressure(x, u, v, p_sp), p, 1e-9 * p);
        EXPECT_NEAR(co.Flow(x, u, v), q, 1e-18);
        const double big_p = p +
                             params.density_kgpm3 * params.gravity_mps2 * params.SinInclination() *
                                 x * params.pipe_length_m -
                             p_sp;
        const double alpha = big_p / rho_c + q / area;
        const double beta = -big_p / rho_c + q / area;
        EXPECT_NEAR(alpha, 2.0 / area * std::exp(-co.sigma * x) * u,
                    1e-12 * (1 + std::fabs(alpha)));
        EXPECT_NEAR(beta, 2.0 / area * std::exp(co.sigma * x) * v, 1e-12 * (1 + std::fabs(beta)));
      }
    }
  }
  // sigma (10.2.7) and epsilon (10.2.3) with the thesis defaults.
  EXPECT_NEAR(co.sigma, 0.15 * 900.0 / (2 * 850.0), 1e-15);
  EXPECT_NEAR(co.epsilon_per_s, 850.0 / 900.0, 1e-15);
}

}  // namespace
}  // namespace mpdrig::observer
