// The mystery rig for teaching: `mpdrig serve --hidden-effect NAME[:k=v] | random [--seed S]`
// runs a rig with a catalogue effect its status does not name; `mpdrig reveal --seed S` tells the
// instructor which effect `random` chose for that seed.
#pragma once

#include <cstdint>
#include <string>

#include "model/common/status.h"

namespace mpdrig::cli {

// "random": one of the catalogue's diagnose candidates drawn with `seed` (std::mt19937_64, its
// first number modulo their count: the same seed gives the same effect with any standard library),
// at its default strength; anything else is returned as the effect spec it is. The spec is checked
// by the caller (ApplyEffectSpec).
std::string ResolveHiddenEffect(const std::string& argument, std::uint64_t seed);

// "column_separation (defaults: ...)" for `mpdrig reveal`.
Result<std::string> DescribeHiddenEffect(const std::string& spec);

}  // namespace mpdrig::cli
