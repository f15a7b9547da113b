// Channel and unit vocabulary of rig-log v1 (docs/rig-log-format.md).
//
// A rig-log column is named `<channel>_<unit>`: `PT3_barg`, `FT2_lpm`, `choke_position_deg`.
// The unit suffix is what follows the last underscore (no unit contains an underscore), so
// `BHP_est_barg` is channel `BHP_est` in bar gauge. Units:
//
//   quantity       suffixes                       SI inside the model
//   time           s                              s
//   position       m                              m
//   choke opening  deg (0 closed .. 90 open), frac fraction 0..1 (u_c = deg / 90)
//   flow           lpm, m3ps                      m^3/s
//   pressure       barg, bara, pag, paa           Pa ABSOLUTE (gauge + atmospheric_pressure_pa)
//
// Suffixes are case-sensitive. The lab's channels (below) have a fixed quantity; a known channel
// with a unit of another quantity (`PT1_lpm`) is an error. Any other channel name is kept and
// takes its quantity from its unit (`piston_ref_m` is a position).
//
// Known channels (positions along the pipe: x = 0 at the heave generator, 900 m at the choke):
//   time                  sample time
//   piston_position       heave generator (BHA) position, positive up
//   choke_position        choke opening (position feedback)
//   FT1 FT2 FT3 FT4       pipe outlet, back-pressure pump, through the choke, pipe inlet
//   P1 P2                 heave generator compartment below / above the BHA
//   PT1 .. PT10           copper pipe at x = 0, 100, ..., 900 m
//   C1 C2                 downstream / upstream of the choke
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "model/common/status.h"

namespace mpdrig::riglog {

enum class Quantity { kTime, kPosition, kChokeOpening, kFlow, kPressure };

enum class Unit { kS, kM, kDeg, kFrac, kLpm, kM3ps, kBarg, kBara, kPag, kPaa };

enum class Channel {
  kTime,
  kPistonPosition,
  kChokePosition,
  kFT1,
  kFT2,
  kFT3,
  kFT4,
  kP1,
  kP2,
  kPT1,
  kPT2,
  kPT3,
  kPT4,
  kPT5,
  kPT6,
  kPT7,
  kPT8,
  kPT9,
  kPT10,
  kC1,
  kC2,
};

struct ChannelInfo {
  Channel channel;
  std::string_view name;  // as written in a column name, e.g. "PT3"
  Quantity quantity;
};

// All known channels, in the order of the Channel enum.
std::span<const ChannelInfo> KnownChannels();
// All units, in the order of the Unit enum.
std::span<const Unit> AllUnits();

std::string_view ChannelName(Channel channel);
Quantity QuantityOf(Channel channel);
// The known channel with exactly this name (case-sensitive), if any.
std::optional<Channel> FindChannel(std::string_view name);

std::string_view QuantityName(Quantity quantity);  // "time", "position", "choke opening", ...

std::string_view UnitSuffix(Unit unit);  // "barg"
Quantity QuantityOf(Unit unit);
bool IsGauge(Unit unit);  // barg, pag
// "s, m, deg, frac, lpm, m3ps, barg, bara, pag, paa"
std::string KnownUnitsList();
// Error lists the known units: "unknown unit suffix 'mm'; known units: s, m, ...".
Result<Unit> ParseUnit(std::string_view suffix);

// Lab-default unit for writing: time s, position m, choke opening deg, flow lpm, pressure barg.
Unit LabUnitFor(Quantity quantity);
// The model's unit: s, m, frac, m3ps, paa.
Unit SiUnitFor(Quantity quantity);

// Unit conversion to and from SI with absolute pressure. `atmospheric_pressure_pa` is used by the
// gauge units only.
double ToSi(Unit unit, double value, double atmospheric_pressure_pa);
double FromSi(Unit unit, double value_si, double atmospheric_pressure_pa);

// One column of a rig log. Invariant (when built by ParseColumnName/MakeColumn):
// name == channel + "_" + UnitSuffix(unit).
struct ColumnSpec {
  std::string name;     // "PT1_barg"
  std::string channel;  // "PT1"
  Unit unit = Unit::kS;

  Quantity quantity() const { return QuantityOf(unit); }
  bool operator==(const ColumnSpec&) const = default;
};

// The time column, `time_s`.
ColumnSpec TimeColumn();

// Splits and checks a column name. Errors (without file position; the reader adds it):
//   no underscore / empty channel / unknown unit suffix (lists known units) /
//   known channel with a unit of the wrong quantity / a channel that differs from a known one
//   only in case (`pt1_barg`) / whitespace, quotes or control characters in the name.
Result<ColumnSpec> ParseColumnName(std::string_view name);
// Builds a column from its parts, with the same checks as ParseColumnName.
Result<ColumnSpec> MakeColumn(std::string_view channel, Unit unit);
// Known channel in its lab-default unit: MakeColumn(ChannelName(c), LabUnitFor(QuantityOf(c))).
ColumnSpec LabColumn(Channel channel);

// The physical range of a sample of `quantity`, SI with absolute pressure (none for time). Wide
// enough for any reading of the lab's rig, with sensor offsets and noise; narrow enough to catch a
// value in the wrong unit, a sign slip or an overflow (1e308 barg is infinite in Pa):
//   position       -10 .. 10 m                  (the heave generator strokes well under 1 m)
//   choke opening  -0.05 .. 1.05 (-4.5 .. 94.5 deg: 0 closed .. 1 open, plus a feedback offset)
//   flow           -0.1 .. 0.1 m^3/s            (+-6000 L/min; the lab's pumps give tens of L/min)
//   pressure       -1000 .. 1000 bar absolute   (a measurement stays above 0 abs but for a
//                                               transmitter's offset; a simulation let past the
//                                               model's range, --allow-negative-pressure, is not)
struct PhysicalRange {
  double min_si = 0.0;
  double max_si = 0.0;
};
std::optional<PhysicalRange> PhysicalRangeOf(Quantity quantity);
// Checks a sample of `column`: `value` as written, `value_si` converted. NaN (not measured)
// passes. The error (no file position; the reader adds it) names the column, the value and the
// range in the column's unit, e.g. "PT1_barg: 1e+308 is outside the physical range of a
// pressure, -1.51325 .. 998.98675 barg".
Status CheckPhysicalRange(const ColumnSpec& column, double value, double value_si,
                          double atmospheric_pressure_pa);

// ---- Field syntax shared by the reader and the writer -------------------------------------

// `# key: value` lines before the header, in file order.
using Metadata = std::vector<std::pair<std::string, std::string>>;

inline constexpr std::string_view kVersionKey = "rig-log";
inline constexpr std::string_view kFormatVersion = "1";
inline constexpr std::string_view kAtmosphericPressureKey = "atmospheric_pressure_pa";

// A metadata key: a letter, then letters, digits, '_', '-' or '.'. `# see: x` is metadata,
// `# a free comment` and `# 12:30 restart` are plain comments.
bool IsMetadataKey(std::string_view key);

// Parses the value of `atmospheric_pressure_pa`: a finite number of Pa within
// [kMinAtmosphericPressurePa, kMaxAtmosphericPressurePa] (so that a value given in bar by mistake
// is caught). The error message names the value but no position.
inline constexpr double kMinAtmosphericPressurePa = 1.0e4;
inline constexpr double kMaxAtmosphericPressurePa = 1.0e6;
Result<double> ParseAtmosphericPressure(std::string_view value);

// Parses one sample field, C locale, independent of the global locale (std::from_chars):
// optional sign, digits with optional '.', optional exponent. An empty field and `nan` (any case)
// are NaN ("not measured"). Anything else (spaces, `inf`, `-nan`, `1,5`, hex, a number that
// overflows a double) is an error whose message quotes the field but names no position.
Result<double> ParseSampleField(std::string_view field);

// A user's text for an error message: in single quotes, control characters as \xNN, shortened
// to 40 characters.
std::string QuoteForMessage(std::string_view text);

// Text that reads back to exactly `value`: the shortest digits (std::to_chars), in fixed
// notation unless scientific is more than 3 characters shorter ("100000", "0.0002", "1e-10",
// "1.5e+20"). NaN -> "" (empty field). `value` must not be infinite.
std::string FormatNumber(double value);
// The same, appended to `out` (no allocation beyond `out`'s growth).
void AppendNumber(double value, std::string* out);

}  // namespace mpdrig::riglog
