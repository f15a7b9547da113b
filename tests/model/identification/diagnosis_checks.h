// Checks shared by diagnose_test and selection_test.
#pragma once

#include <gtest/gtest.h>

#include "model/identification/diagnose.h"

namespace mpdrig {

// "Within rounding": the fitting error is a mean NRMSE of a few percent printed to 4 digits; a
// candidate whose zero strength only nears the base model (a compartment at 2.5 GPa rather than
// rigid) may sit this far above it.
inline constexpr double kFitErrorRounding = 1.0e-4;

// Never worse than the base model on the data it was fitted on, every candidate of the log:
// at most its error with the effect at zero strength, which is the base model's own, for every
// effect but piston_compressibility (its bulk modulus is bounded at 2.5 GPa, a compartment
// that is not quite the base model's rigid one: there the bound is the nearest it comes).
inline void ExpectNeverWorseThanTheBaseModel(const Diagnosis& d) {
  for (const CandidateResult& c : d.candidates) {
    EXPECT_LE(c.fit_error, c.zero_fit_error * (1.0 + kFitErrorRounding))
        << c.effect << ": fitting error " << c.fit_error << " above its zero strength's "
        << c.zero_fit_error;
    if (c.effect == "piston_compressibility") continue;
    EXPECT_LE(c.fit_error, d.baseline.fit_error * (1.0 + kFitErrorRounding))
        << c.effect << ": fitting error " << c.fit_error << " against the base model's "
        << d.baseline.fit_error;
  }
}

}  // namespace mpdrig
