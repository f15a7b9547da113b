#include "model/riglog/channels.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

#include "model/common/units.h"

namespace mpdrig::riglog {
namespace {

constexpr std::array<ChannelInfo, 21> kChannels = {{
    {Channel::kTime, "time", Quantity::kTime},
    {Channel::kPistonPosition, "piston_position", Quantity::kPosition},
    {Channel::kChokePosition, "choke_position", Quantity::kChokeOpening},
    {Channel::kFT1, "FT1", Quantity::kFlow},
    {Channel::kFT2, "FT2", Quantity::kFlow},
    {Channel::kFT3, "FT3", Quantity::kFlow},
    {Channel::kFT4, "FT4", Quantity::kFlow},
    {Channel::kP1, "P1", Quantity::kPressure},
    {Channel::kP2, "P2", Quantity::kPressure},
    {Channel::kPT1, "PT1", Quantity::kPressure},
    {Channel::kPT2, "PT2", Quantity::kPressure},
    {Channel::kPT3, "PT3", Quantity::kPressure},
    {Channel::kPT4, "PT4", Quantity::kPressure},
    {Channel::kPT5, "PT5", Quantity::kPressure},
    {Channel::kPT6, "PT6", Quantity::kPressure},
    {Channel::kPT7, "PT7", Quantity::kPressure},
    {Channel::kPT8, "PT8", Quantity::kPressure},
    {Channel::kPT9, "PT9", Quantity::kPressure},
    {Channel::kPT10, "PT10", Quantity::kPressure},
    {Channel::kC1, "C1", Quantity::kPressure},
    {Channel::kC2, "C2", Quantity::kPressure},
}};

struct UnitInfo {
  Unit unit;
  std::string_view suffix;
  Quantity quantity;
};

constexpr std::array<UnitInfo, 10> kUnits = {{
    {Unit::kS, "s", Quantity::kTime},
    {Unit::kM, "m", Quantity::kPosition},
    {Unit::kDeg, "deg", Quantity::kChokeOpening},
    {Unit::kFrac, "frac", Quantity::kChokeOpening},
    {Unit::kLpm, "lpm", Quantity::kFlow},
    {Unit::kM3ps, "m3ps", Quantity::kFlow},
    {Unit::kBarg, "barg", Quantity::kPressure},
    {Unit::kBara, "bara", Quantity::kPressure},
    {Unit::kPag, "pag", Quantity::kPressure},
    {Unit::kPaa, "paa", Quantity::kPressure},
}};

constexpr std::array<Unit, 10> kAllUnits = {Unit::kS,   Unit::kM,    Unit::kDeg,  Unit::kFrac,
                                            Unit::kLpm, Unit::kM3ps, Unit::kBarg, Unit::kBara,
                                            Unit::kPag, Unit::kPaa};

const UnitInfo& InfoOf(Unit unit) {
  const auto index = static_cast<std::size_t>(unit);
  MPDRIG_CHECK(index < kUnits.size() && kUnits[index].unit == unit);
  return kUnits[index];
}

const ChannelInfo& InfoOf(Channel channel) {
  const auto index = static_cast<std::size_t>(channel);
  MPDRIG_CHECK(index < kChannels.size() && kChannels[index].channel == channel);
  return kChannels[index];
}

bool EqualsIgnoringCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

// Characters that cannot appear in a column name: the separator, CSV quoting, whitespace and
// control characters (a name with them could not be written back unambiguously).
bool IsForbiddenNameChar(char c) {
  const auto u = static_cast<unsigned char>(c);
  return c == ',' || c == '"' || c == ' ' || c == '\t' || u < 0x20 || u == 0x7f;
}

// Checks channel + unit; `name` is only used in messages.
Status CheckColumn(std::string_view name, std::string_view channel, Unit unit) {
  if (channel.empty()) {
    return Status::Error("column " + QuoteForMessage(name) + " has an empty channel name");
  }
  for (char c : name) {
    if (IsForbiddenNameChar(c)) {
      return Status::Error("column " + QuoteForMessage(name) +
                           " contains a space, tab, comma, quote or control character");
    }
  }
  const std::optional<Channel> known = FindChannel(channel);
  if (known.has_value()) {
    if (QuantityOf(*known) != QuantityOf(unit)) {
      std::string valid;
      for (const UnitInfo& info : kUnits) {
        if (info.quantity != QuantityOf(*known)) continue;
        if (!valid.empty()) valid += ", ";
        valid += info.suffix;
      }
      return Status::Error("column " + QuoteForMessage(name) + ": channel " +
                           QuoteForMessage(channel) + " is a " +
                           std::string(QuantityName(QuantityOf(*known))) + ", but unit " +
                           QuoteForMessage(UnitSuffix(unit)) + " is a " +
                           std::string(QuantityName(QuantityOf(unit))) + "; valid units: " + valid);
    }
    return Status::Ok();
  }
  for (const ChannelInfo& info : kChannels) {
    if (EqualsIgnoringCase(channel, info.name)) {
      return Status::Error("column " + QuoteForMessage(name) + ": channel " +
                           QuoteForMessage(channel) + " differs from the known channel " +
                           QuoteForMessage(info.name) +
                           " only in case; channel names are case-sensitive");
    }
  }
  return Status::Ok();
}

}  // namespace

std::string QuoteForMessage(std::string_view s) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < kMaxShown; ++i) {
    const auto u = static_cast<unsigned char>(s[i]);
    if (u < 0x20 || u == 0x7f) {
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0xf];
    } else {
      out += s[i];
    }
  }
  if (s.size() > kMaxShown) out += "...";
  return out + "'";
}

std::span<const ChannelInfo> KnownChannels() { return kChannels; }
std::span<const Unit> AllUnits() { return kAllUnits; }

std::string_view ChannelName(Channel channel) { return InfoOf(channel).name; }
Quantity QuantityOf(Channel channel) { return InfoOf(channel).quantity; }

std::optional<Channel> FindChannel(std::string_view name) {
  for (const ChannelInfo& info : kChannels) {
    if (info.name == name) return info.channel;
  }
  return std::nullopt;
}

std::string_view QuantityName(Quantity quantity) {
  switch (quantity) {
    case Quantity::kTime:
      return "time";
    case Quantity::kPosition:
      return "position";
    case Quantity::kChokeOpening:
      return "choke opening";
    case Quantity::kFlow:
      return "flow";
    case Quantity::kPressure:
      return "pressure";
  }
  MPDRIG_CHECK(false);
  return "";
}

std::string_view UnitSuffix(Unit unit) { return InfoOf(unit).suffix; }
Quantity QuantityOf(Unit unit) { return InfoOf(unit).quantity; }
bool IsGauge(Unit unit) { return unit == Unit::kBarg || unit == Unit::kPag; }

std::string KnownUnitsList() {
  std::string list;
  for (const UnitInfo& info : kUnits) {
    if (!list.empty()) list += ", ";
    list += info.suffix;
  }
  return list;
}

Result<Unit> ParseUnit(std::string_view suffix) {
  for (const UnitInfo& info : kUnits) {
    if (info.suffix == suffix) return info.unit;
  }
  return Status::Error("unknown unit suffix " + QuoteForMessage(suffix) +
                       "; known units: " + KnownUnitsList());
}

Unit LabUnitFor(Quantity quantity) {
  switch (quantity) {
    case Quantity::kTime:
      return Unit::kS;
    case Quantity::kPosition:
      return Unit::kM;
    case Quantity::kChokeOpening:
      return Unit::kDeg;
    case Quantity::kFlow:
      return Unit::kLpm;
    case Quantity::kPressure:
      return Unit::kBarg;
  }
  MPDRIG_CHECK(false);
  return Unit::kS;
}

Unit SiUnitFor(Quantity quantity) {
  switch (quantity) {
    case Quantity::kTime:
      return Unit::kS;
    case Quantity::kPosition:
      return Unit::kM;
    case Quantity::kChokeOpening:
      return Unit::kFrac;
    case Quantity::kFlow:
      return Unit::kM3ps;
    case Quantity::kPressure:
      return Unit::kPaa;
  }
  MPDRIG_CHECK(false);
  return Unit::kS;
}

double ToSi(Unit unit, double value, double atmospheric_pressure_pa) {
  switch (unit) {
    case Unit::kS:
    case Unit::kM:
    case Unit::kFrac:
    case Unit::kM3ps:
    case Unit::kPaa:
      return value;
    case Unit::kDeg:
      return units::ChokeDegToFrac(value);
    case Unit::kLpm:
      return units::LpmToM3ps(value);
    case Unit::kBarg:
      return units::BargToPaAbs(value, atmospheric_pressure_pa);
    case Unit::kBara:
      return units::BarToPa(value);
    case Unit::kPag:
      return units::GaugeToAbsolutePa(value, atmospheric_pressure_pa);
  }
  MPDRIG_CHECK(false);
  return 0.0;
}

double FromSi(Unit unit, double value_si, double atmospheric_pressure_pa) {
  switch (unit) {
    case Unit::kS:
    case Unit::kM:
    case Unit::kFrac:
    case Unit::kM3ps:
    case Unit::kPaa:
      return value_si;
    case Unit::kDeg:
      return units::ChokeFracToDeg(value_si);
    case Unit::kLpm:
      return units::M3psToLpm(value_si);
    case Unit::kBarg:
      return units::PaAbsToBarg(value_si, atmospheric_pressure_pa);
    case Unit::kBara:
      return units::PaToBar(value_si);
    case Unit::kPag:
      return value_si - atmospheric_pressure_pa;
  }
  MPDRIG_CHECK(false);
  return 0.0;
}

ColumnSpec TimeColumn() { return ColumnSpec{"time_s", "time", Unit::kS}; }

Result<ColumnSpec> ParseColumnName(std::string_view name) {
  if (name.empty()) return Status::Error("empty column name");
  const std::size_t underscore = name.rfind('_');
  if (underscore == std::string_view::npos) {
    return Status::Error("column " + QuoteForMessage(name) +
                         " has no unit suffix; a column is named <channel>_<unit>, known units: " +
                         KnownUnitsList());
  }
  const std::string_view channel = name.substr(0, underscore);
  const std::string_view suffix = name.substr(underscore + 1);
  Result<Unit> unit = ParseUnit(suffix);
  if (!unit.ok()) {
    return Status::Error("unknown unit suffix " + QuoteForMessage(suffix) + " in column " +
                         QuoteForMessage(name) + "; known units: " + KnownUnitsList());
  }
  MPDRIG_RETURN_IF_ERROR(CheckColumn(name, channel, *unit));
  return ColumnSpec{std::string(name), std::string(channel), *unit};
}

Result<ColumnSpec> MakeColumn(std::string_view channel, Unit unit) {
  std::string name = std::string(channel) + "_" + std::string(UnitSuffix(unit));
  MPDRIG_RETURN_IF_ERROR(CheckColumn(name, channel, unit));
  return ColumnSpec{std::move(name), std::string(channel), unit};
}

ColumnSpec LabColumn(Channel channel) {
  Result<ColumnSpec> column = MakeColumn(ChannelName(channel), LabUnitFor(QuantityOf(channel)));
  MPDRIG_CHECK(column.ok());
  return std::move(column).value();
}

bool IsMetadataKey(std::string_view key) {
  if (key.empty() || !std::isalpha(static_cast<unsigned char>(key[0]))) return false;
  for (char c : key) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') {
      return false;
    }
  }
  return true;
}

Result<double> ParseAtmosphericPressure(std::string_view value) {
  const std::string prefix = std::string(kAtmosphericPressureKey) + ": ";
  if (value.empty()) return Status::Error(prefix + "empty value");
  Result<double> pa = ParseSampleField(value);
  if (!pa.ok()) return Status::Error(prefix + pa.status().message());
  if (std::isnan(*pa)) return Status::Error(prefix + QuoteForMessage(value) + " is not a number");
  if (*pa < kMinAtmosphericPressurePa || *pa > kMaxAtmosphericPressurePa) {
    return Status::Error(prefix + QuoteForMessage(value) +
                         " is not an atmospheric pressure in Pa (expected " +
                         FormatNumber(kMinAtmosphericPressurePa) + " .. " +
                         FormatNumber(kMaxAtmosphericPressurePa) + " Pa)");
  }
  return *pa;
}

Result<double> ParseSampleField(std::string_view field) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (field.empty() || EqualsIgnoringCase(field, "nan")) return kNaN;
  // from_chars takes '-' but not '+'; a single leading '+' is valid C-locale syntax.
  std::string_view digits = field;
  if (digits[0] == '+') {
    digits.remove_prefix(1);
    if (digits.empty() || digits[0] == '+' || digits[0] == '-') {
      return Status::Error(QuoteForMessage(field) + " is not a number");
    }
  }
  double value = 0.0;
  const char* const end = digits.data() + digits.size();
  const auto [ptr, ec] = std::from_chars(digits.data(), end, value, std::chars_format::general);
  if (ec == std::errc::result_out_of_range) {
    return Status::Error(QuoteForMessage(field) + " is out of the range of a double");
  }
  if (ec != std::errc() || ptr != end)
    return Status::Error(QuoteForMessage(field) + " is not a number");
  if (!std::isfinite(value)) {
    return Status::Error(QuoteForMessage(field) +
                         " is not a finite number (write an empty field or 'nan' if not measured)");
  }
  return value;
}

namespace {

// Both forms by two conversions, as std::to_chars gives them: the reference AppendNumber follows
// exactly, and the form for magnitudes where the fixed digits of an integer need not be the
// shortest ones padded with zeros (at 2^53 and above).
void AppendNumberByTwoConversions(double value, std::string* out) {
  char scientific[64];
  const auto [scientific_end, scientific_ec] =
      std::to_chars(scientific, scientific + sizeof(scientific), value);
  MPDRIG_CHECK(scientific_ec == std::errc());
  char fixed[400];  // up to 309 integer digits, or a long fraction
  const auto [fixed_end, fixed_ec] =
      std::to_chars(fixed, fixed + sizeof(fixed), value, std::chars_format::fixed);
  if (fixed_ec == std::errc() && (fixed_end - fixed) <= (scientific_end - scientific) + 3) {
    out->append(fixed, fixed_end);
  } else {
    out->append(scientific, scientific_end);
  }
}

}  // namespace

void AppendNumber(double value, std::string* out) {
  if (std::isnan(value)) return;
  MPDRIG_CHECK(std::isfinite(value));
  // Both forms are the shortest digits that read back exactly; fixed notation is easier on the
  // eye ("100000", "0.0002"), so it wins unless it is more than 3 characters longer. (std::
  // to_chars without a format gives the shorter of the two, so "fixed unless longer than it + 3"
  // is "fixed unless longer than scientific + 3".)
  //
  // One shortest conversion (Ryu's digits d1...dn and exponent e, in scientific form) and the
  // fixed form written from the same digits: a log writes tens of thousands of numbers, and the
  // second conversion was half the writer's time. Below 2^53 the two conversions agree: the
  // shortest fixed text has the fewest fraction digits that read back, which are the shortest
  // digits placed at their exponent, and where those end in zeros before the point (e >= n - 1)
  // the integer they spell reads back to the value, so the value is that integer (every integer
  // below 2^53 is a double), whose exact digits the fixed form also picks. Above, the reference.
  // RigLogChannels.FormatNumberIsWhatTwoConversionsGive (channels_test) checks the bytes
  // against it.
  if (!(std::fabs(value) < 0x1p53)) {
    AppendNumberByTwoConversions(value, out);
    return;
  }
  char scientific[64];
  const auto [end, ec] = std::to_chars(scientific, scientific + sizeof(scientific), value,
                                       std::chars_format::scientific);
  MPDRIG_CHECK(ec == std::errc());
  // "-d.ddde+XX": sign, digits (the point after the first), exponent.
  const char* p = scientific;
  const bool negative = *p == '-';
  if (negative) ++p;
  char digits[20];
  int n = 0;
  for (; *p != 'e'; ++p) {
    if (*p != '.') digits[n++] = *p;
  }
  int exponent = 0;
  std::from_chars(p + (p[1] == '+' ? 2 : 1), end, exponent);
  const std::ptrdiff_t scientific_length = end - scientific;
  // The fixed form's length: sign, integer digits, point and fraction digits.
  const int integer_digits = exponent >= 0 ? exponent + 1 : 1;
  const int fraction_digits = exponent >= 0 ? std::max(n - 1 - exponent, 0) : n - 1 - exponent;
  const std::ptrdiff_t fixed_length =
      (negative ? 1 : 0) + integer_digits + (fraction_digits > 0 ? 1 + fraction_digits : 0);
  if (fixed_length > scientific_length + 3) {
    out->append(scientific, end);
    return;
  }
  if (negative) out->push_back('-');
  if (exponent >= 0) {
    for (int i = 0; i < integer_digits; ++i) out->push_back(i < n ? digits[i] : '0');
    if (fraction_digits > 0) {
      out->push_back('.');
      out->append(digits + integer_digits, digits + n);
    }
  } else {
    out->append("0.");
    out->append(static_cast<std::size_t>(-exponent - 1), '0');
    out->append(digits, digits + n);
  }
}

std::optional<PhysicalRange> PhysicalRangeOf(Quantity quantity) {
  switch (quantity) {
    case Quantity::kTime:
      return std::nullopt;
    case Quantity::kPosition:
      return PhysicalRange{-10.0, 10.0};
    case Quantity::kChokeOpening:
      return PhysicalRange{-0.05, 1.05};
    case Quantity::kFlow:
      return PhysicalRange{-0.1, 0.1};
    case Quantity::kPressure:
      return PhysicalRange{-1.0e8, 1.0e8};
  }
  MPDRIG_CHECK(false);
  return std::nullopt;
}

Status CheckPhysicalRange(const ColumnSpec& column, double value, double value_si,
                          double atmospheric_pressure_pa) {
  if (std::isnan(value) && std::isnan(value_si)) return Status::Ok();
  const std::optional<PhysicalRange> range = PhysicalRangeOf(column.quantity());
  if (!range || (value_si >= range->min_si && value_si <= range->max_si)) return Status::Ok();
  const double low = FromSi(column.unit, range->min_si, atmospheric_pressure_pa);
  const double high = FromSi(column.unit, range->max_si, atmospheric_pressure_pa);
  return Status::Error(column.name + ": " + FormatNumber(value) +
                       " is outside the physical range of a " +
                       std::string(QuantityName(column.quantity())) + ", " + FormatNumber(low) +
                       " .. " + FormatNumber(high) + " " + std::string(UnitSuffix(column.unit)));
}

std::string FormatNumber(double value) {
  std::string text;
  AppendNumber(value, &text);
  return text;
}

}  // namespace mpdrig::riglog
