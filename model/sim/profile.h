// Parametric input profiles: what a lab user types to drive the piston or the choke.
//
//   <number>                                   constant
//   sine:amp_U=A,freq_hz=F[,mean_U=M][,phase_deg=P]      M + A sin(2 pi F t + P)
//   sweep:amp_U=A,f0_hz=F0,f1_hz=F1[,duration_s=T][,mean_U=M]
//                                              linear chirp M + A sin(2 pi (F0 t + (F1-F0)
//                                              t^2/(2T)))
//   step:amp_U=A,t_s=T0[,rise_s=R][,mean_U=M]   M until T0, then a ramp of R seconds to M + A
//
// U is the profile's unit: "m" for the piston position, "deg" for the choke opening. Values are
// returned in that unit; the caller converts. Unknown keys, missing keys and non-finite values
// are errors that list what is accepted.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "model/common/status.h"

namespace mpdrig {

class Profile {
 public:
  virtual ~Profile() = default;
  virtual double ValueAt(double time_s) const = 0;
  virtual std::string Describe() const = 0;
};

// `default_duration_s` is the sweep duration when the spec does not give one.
Result<std::unique_ptr<Profile>> ParseProfile(std::string_view spec, std::string_view unit,
                                              double default_duration_s);

}  // namespace mpdrig
