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

// Every selection round after the first is reported (Diagnosis::later_rounds): one per effect
// selected after the verdict, plus the round that ended the selection where one did; each ranks
// the effect it selected first, and the ending round's first candidate is `next`.
inline void ExpectEveryRoundReported(const Diagnosis& d) {
  if (d.selected.empty()) {
    EXPECT_TRUE(d.later_rounds.empty());
    return;
  }
  const bool ended_in_a_round = d.selection_end == "no candidate significant" ||
                                d.selection_end == "no candidate could be fitted";
  ASSERT_EQ(d.later_rounds.size(), d.selected.size() - 1 + (ended_in_a_round ? 1 : 0))
      << d.selection_end;
  for (std::size_t r = 0; r < d.later_rounds.size(); ++r) {
    for (const CandidateResult& c : d.later_rounds[r]) {
      EXPECT_EQ(c.round, static_cast<int>(r) + 2) << c.effect;
    }
    if (r + 1 < d.selected.size()) {
      ASSERT_FALSE(d.later_rounds[r].empty());
      EXPECT_EQ(d.later_rounds[r].front().effect, d.selected[r + 1].effect);
    }
  }
  if (ended_in_a_round && !d.later_rounds.back().empty()) {
    ASSERT_TRUE(d.next.has_value());
    EXPECT_EQ(d.next->effect, d.later_rounds.back().front().effect);
  }
}

}  // namespace mpdrig
