// The rig's channels as the simulator produces them: the lab's channel vocabulary of the rig log
// (model/riglog/channels.h), so a simulated sample is a rig-log row. Values inside the model are
// SI with absolute pressure: s, m, fraction of full opening, Pa, m^3/s.
#pragma once

#include <array>
#include <cstddef>

#include "model/riglog/channels.h"

namespace mpdrig {

using riglog::Channel;

inline constexpr std::size_t kChannelCount = static_cast<std::size_t>(Channel::kC2) + 1;
constexpr std::size_t Index(Channel channel) { return static_cast<std::size_t>(channel); }

// Every channel of a rig sample, SI with absolute pressure, indexed by Index(Channel).
using ChannelValues = std::array<double, kChannelCount>;

// PTk sits at x = 100 (k - 1) m on the 900 m pipe: fraction (k - 1)/9 of the pipe length.
inline constexpr int kPipeTransmitterCount = 10;

}  // namespace mpdrig
