// Lab units at the edges, SI inside (style.md). Conversions between the rig's engineering units
// (bar gauge, litres per minute, degrees of choke opening) and the model's SI units with absolute
// pressure. The choke opening u_c is a fraction in [0, 1] inside the model (thesis symbol table);
// the lab's choke runs 0 (closed) .. 90 deg (fully open), rig-log-format.md.
#pragma once

namespace mpdrig::units {

inline constexpr double kStandardAtmospherePa = 101325.0;
inline constexpr double kPaPerBar = 1.0e5;
inline constexpr double kM3psPerLpm = 1.0e-3 / 60.0;
inline constexpr double kChokeFullOpenDeg = 90.0;

constexpr double BarToPa(double bar) { return bar * kPaPerBar; }
constexpr double PaToBar(double pa) { return pa / kPaPerBar; }
constexpr double GaugeToAbsolutePa(double gauge_pa, double atmospheric_pa) {
  return gauge_pa + atmospheric_pa;
}
constexpr double BargToPaAbs(double barg, double atmospheric_pa) {
  return BarToPa(barg) + atmospheric_pa;
}
constexpr double PaAbsToBarg(double pa_abs, double atmospheric_pa) {
  return PaToBar(pa_abs - atmospheric_pa);
}
constexpr double LpmToM3ps(double lpm) { return lpm * kM3psPerLpm; }
constexpr double M3psToLpm(double m3ps) { return m3ps / kM3psPerLpm; }
constexpr double ChokeDegToFrac(double deg) { return deg / kChokeFullOpenDeg; }
constexpr double ChokeFracToDeg(double frac) { return frac * kChokeFullOpenDeg; }

}  // namespace mpdrig::units
