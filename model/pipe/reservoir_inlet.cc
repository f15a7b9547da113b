#include "model/pipe/reservoir_inlet.h"

#include "model/common/root_finding.h"

namespace mpdrig {

double ReservoirInlet::SolveInletVelocity(const BoundaryRelation& pipe,
                                          const InletInputs& /*inputs*/) const {
  // g(u) = p_R - p(u) is strictly decreasing (the pipe's impedance, rho c for the linear model).
  // The guess 0 costs the linear model nothing (g is linear); 1 m/s steps bound the search where
  // a relation has no slope (a vapour cavity at the node, which p_R > p_v never lets open).
  return SolveDecreasing(
      0.0, 1.0, [&](double u) { return pressure_pa_ - pipe.PressurePa(u); },
      [&](double u) { return -pipe.DPressureDVelocity(u); });
}

}  // namespace mpdrig
