// sensor_lag: pressure transmitter dynamics, a first-order lag on every pressure channel the
// model computes (P1, P2, PT1..PT10, C2):
//   T dy/dt = p - y,   discretised exactly for p held over a step: y += (1 - exp(-dt/T)) (p - y).
// The transmitters' own dynamics are not in the thesis; a lag shows as a phase lag of every
// pressure channel that grows with frequency (phase -atan(2 pi f T)) and a small amplitude loss,
// while the flow meters stay on time.
#include <cmath>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

constexpr Channel kLaggedChannels[] = {
    Channel::kP1,  Channel::kP2,  Channel::kPT1, Channel::kPT2, Channel::kPT3,
    Channel::kPT4, Channel::kPT5, Channel::kPT6, Channel::kPT7, Channel::kPT8,
    Channel::kPT9, Channel::kPT10, Channel::kC2};

class SensorLag final : public Effect {
 public:
  explicit SensorLag(double time_constant_s) : time_constant_s_(time_constant_s) {}

  void Initialize(const PipeSolver&, const ChannelValues& channels) override {
    for (Channel channel : kLaggedChannels) state_[Index(channel)] = channels[Index(channel)];
  }
  bool filters_sensors() const override { return true; }
  void FilterSensors(ChannelValues* values, double dt_s) override {
    const double gain = time_constant_s_ > 0.0 ? -std::expm1(-dt_s / time_constant_s_) : 1.0;
    for (Channel channel : kLaggedChannels) {
      double& y = state_[Index(channel)];
      y += gain * ((*values)[Index(channel)] - y);
      (*values)[Index(channel)] = y;
    }
  }

 private:
  double time_constant_s_;
  ChannelValues state_{};
};

}  // namespace

const EffectInfo& SensorLagEffect() {
  static const EffectInfo info{
      "sensor_lag",
      "pressure transmitters as first-order lags: T dy/dt = p - y",
      "not in the thesis (its transmitters are taken as ideal, 8.1)",
      "removes a phase lag of every pressure channel that grows with frequency, while the flow "
      "meters stay on time",
      {{"time_constant_s", "s", "transmitter time constant T", 0.05, 0.0, 1.0, true}},
      [](const EffectContext& context) {
        return std::make_unique<SensorLag>(context.Get("time_constant_s"));
      }};
  return info;
}

}  // namespace mpdrig
