#include "tools/report/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace mpdrig::report {
namespace {

constexpr int kLeftPx = 64, kRightPx = 12, kTopPx = 10, kBottomPx = 38;

// Round tick positions covering [lo, hi]: steps of 1, 2 or 5 times a power of ten.
std::vector<double> LinearTicks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  // At most a few times the target: a step below the values' resolution (t + step == t) would
  // otherwise never end. SvgPlot::FixRanges keeps ranges above it; this is the backstop.
  const std::size_t most = 4 * static_cast<std::size_t>(std::max(target, 1)) + 1;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step && ticks.size() < most;
       t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::vector<double> LogTicks(double lo, double hi) {
  std::vector<double> ticks;
  if (hi - lo < 1.0) {  // within a decade: round values, placed on the log axis
    for (double t : LinearTicks(std::pow(10.0, lo), std::pow(10.0, hi), 4)) {
      if (t > 0.0) ticks.push_back(std::log10(t));
    }
    return ticks;
  }
  for (double e = std::floor(lo); e <= std::ceil(hi); e += 1.0) {
    if (e >= lo - 1e-9 && e <= hi + 1e-9) ticks.push_back(e);
  }
  return ticks;
}

std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", v);
  return buffer;
}

// A range no wider than the rounding of its values (a constant that reads 5 and 5 + 1 ulp): a
// point, as far as axis labels of a few digits can tell.
bool WithinRounding(double lo, double hi) {
  return !(hi - lo > 1e-9 * std::max(std::abs(lo), std::abs(hi)));
}

}  // namespace

std::string FormatValue(double value, int digits) {
  if (!std::isfinite(value)) return "&ndash;";
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

std::string EscapeHtml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

SvgPlot::SvgPlot(int width_px, int height_px, std::string x_label, std::string y_label)
    : width_(width_px),
      height_(height_px),
      x_label_(std::move(x_label)),
      y_label_(std::move(y_label)),
      x_lo_(std::numeric_limits<double>::infinity()),
      x_hi_(-std::numeric_limits<double>::infinity()),
      y_lo_(std::numeric_limits<double>::infinity()),
      y_hi_(-std::numeric_limits<double>::infinity()) {}

void SvgPlot::Extend(const std::vector<double>& x, const std::vector<double>& y) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double xv = log_x_ ? (x[i] > 0 ? std::log10(x[i]) : NAN) : x[i];
    if (std::isfinite(xv)) x_lo_ = std::min(x_lo_, xv), x_hi_ = std::max(x_hi_, xv);
    if (i < y.size() && !y_fixed_) {
      const double yv = log_y_ ? (y[i] > 0 ? std::log10(y[i]) : NAN) : y[i];
      if (std::isfinite(yv)) y_lo_ = std::min(y_lo_, yv), y_hi_ = std::max(y_hi_, yv);
    }
  }
}

void SvgPlot::Line(const std::vector<double>& x, const std::vector<double>& y,
                   const std::string& color, double width_px, const std::string& dash) {
  Extend(x, y);
  items_.push_back({"line", x, y, {}, color, dash, width_px});
}

void SvgPlot::Band(const std::vector<double>& x, const std::vector<double>& lo,
                   const std::vector<double>& hi, const std::string& color, double opacity) {
  Extend(x, lo);
  Extend(x, hi);
  items_.push_back({"band", x, lo, hi, color, "", opacity});
}

void SvgPlot::Markers(const std::vector<double>& x, const std::vector<double>& y,
                      const std::string& color, double radius_px) {
  Extend(x, y);
  items_.push_back({"markers", x, y, {}, color, "", radius_px});
}

void SvgPlot::HorizontalLine(double y, const std::string& color, const std::string& dash) {
  Extend({}, {});
  if (!y_fixed_ && std::isfinite(y)) y_lo_ = std::min(y_lo_, y), y_hi_ = std::max(y_hi_, y);
  items_.push_back({"hline", {}, {y}, {}, color, dash, 1.0});
}

void SvgPlot::Stems(const std::vector<double>& x, const std::vector<double>& y,
                    const std::string& color) {
  Extend(x, y);
  if (!y_fixed_) y_lo_ = std::min(y_lo_, 0.0), y_hi_ = std::max(y_hi_, 0.0);
  items_.push_back({"stems", x, y, {}, color, "", 1.5});
}

void SvgPlot::Legend(const std::string& label, const std::string& color) {
  legend_.emplace_back(label, color);
}

void SvgPlot::SetYRange(double lo, double hi) {
  y_fixed_ = true;
  y_lo_ = log_y_ ? std::log10(lo) : lo;
  y_hi_ = log_y_ ? std::log10(hi) : hi;
}

double SvgPlot::Tx(double x) const {
  const double v = log_x_ ? std::log10(x) : x;
  return kLeftPx + (v - rx_lo_) / (rx_hi_ - rx_lo_) * (width_ - kLeftPx - kRightPx);
}

double SvgPlot::Ty(double y) const {
  const double v = log_y_ ? std::log10(y) : y;
  return height_ - kBottomPx - (v - ry_lo_) / (ry_hi_ - ry_lo_) * (height_ - kTopPx - kBottomPx);
}

std::string SvgPlot::Render() const {
  FixRanges();
  std::string svg = RenderFrameAndAxes();
  for (const Item& item : items_) {
    if (item.kind == "line") {
      svg += RenderLine(item);
    } else if (item.kind == "band") {
      svg += RenderBand(item);
    } else if (item.kind == "markers") {
      svg += RenderMarkers(item);
    } else if (item.kind == "hline") {
      const double py = Ty(item.y[0]);
      svg += "<line x1=\"" + std::to_string(kLeftPx) + "\" y1=\"" + Num(py) + "\" x2=\"" +
             Num(kLeftPx + PlotWidth()) + "\" y2=\"" + Num(py) + "\" stroke=\"" + item.color +
             "\" stroke-dasharray=\"" + item.dash + "\"/>";
    } else if (item.kind == "stems") {
      svg += RenderStems(item);
    }
  }
  svg += "</svg>";
  svg += RenderLegend();
  svg += "</svg>";
  return svg;
}

double SvgPlot::PlotWidth() const { return width_ - kLeftPx - kRightPx; }
double SvgPlot::PlotHeight() const { return height_ - kTopPx - kBottomPx; }

// The drawn ranges from the data's: a default where there is none, a width where it is a point
// (or within rounding of one), and 5 % padding in y unless SetYRange fixed it.
void SvgPlot::FixRanges() const {
  rx_lo_ = std::isfinite(x_lo_) ? x_lo_ : 0.0;
  rx_hi_ = std::isfinite(x_hi_) ? x_hi_ : 1.0;
  ry_lo_ = std::isfinite(y_lo_) ? y_lo_ : 0.0;
  ry_hi_ = std::isfinite(y_hi_) ? y_hi_ : 1.0;
  if (WithinRounding(rx_lo_, rx_hi_)) rx_lo_ = rx_hi_ = 0.5 * (rx_lo_ + rx_hi_);
  if (WithinRounding(ry_lo_, ry_hi_)) ry_lo_ = ry_hi_ = 0.5 * (ry_lo_ + ry_hi_);
  if (!(rx_hi_ > rx_lo_)) rx_lo_ -= 0.5, rx_hi_ += 0.5;
  if (!(ry_hi_ > ry_lo_)) {
    const double pad = std::max(1e-12, std::abs(ry_lo_) * 0.05);
    ry_lo_ -= pad, ry_hi_ += pad;
  } else if (!y_fixed_) {
    const double pad = 0.05 * (ry_hi_ - ry_lo_);
    ry_lo_ -= pad, ry_hi_ += pad;
  }
}

// The outer SVG, the plot's frame, grid, ticks and axis labels, and the opening of the clipped
// inner SVG the items are drawn in.
std::string SvgPlot::RenderFrameAndAxes() const {
  const double plot_w = PlotWidth(), plot_h = PlotHeight();
  // Inline SVG in HTML5 needs no namespace attribute (and the report carries no URL at all).
  std::string svg = "<svg width=\"" + std::to_string(width_) + "\" height=\"" +
                    std::to_string(height_) + "\" viewBox=\"0 0 " + std::to_string(width_) + " " +
                    std::to_string(height_) + "\" font-family=\"sans-serif\" font-size=\"11\">";
  svg += "<rect x=\"" + std::to_string(kLeftPx) + "\" y=\"" + std::to_string(kTopPx) +
         "\" width=\"" + Num(plot_w) + "\" height=\"" + Num(plot_h) +
         "\" fill=\"#fff\" stroke=\"#999\"/>";
  const auto x_ticks = log_x_ ? LogTicks(rx_lo_, rx_hi_) : LinearTicks(rx_lo_, rx_hi_, 8);
  const auto y_ticks = log_y_ ? LogTicks(ry_lo_, ry_hi_) : LinearTicks(ry_lo_, ry_hi_, 5);
  for (double t : x_ticks) {
    const double px = kLeftPx + (t - rx_lo_) / (rx_hi_ - rx_lo_) * plot_w;
    svg += "<line x1=\"" + Num(px) + "\" y1=\"" + std::to_string(kTopPx) + "\" x2=\"" + Num(px) +
           "\" y2=\"" + Num(kTopPx + plot_h) + "\" stroke=\"#eee\"/>";
    svg += "<text x=\"" + Num(px) + "\" y=\"" + Num(kTopPx + plot_h + 14) +
           "\" text-anchor=\"middle\">" + FormatValue(log_x_ ? std::pow(10.0, t) : t, 4) +
           "</text>";
  }
  for (double t : y_ticks) {
    const double py = kTopPx + plot_h - (t - ry_lo_) / (ry_hi_ - ry_lo_) * plot_h;
    svg += "<line x1=\"" + std::to_string(kLeftPx) + "\" y1=\"" + Num(py) + "\" x2=\"" +
           Num(kLeftPx + plot_w) + "\" y2=\"" + Num(py) + "\" stroke=\"#eee\"/>";
    svg += "<text x=\"" + std::to_string(kLeftPx - 4) + "\" y=\"" + Num(py + 4) +
           "\" text-anchor=\"end\">" + FormatValue(log_y_ ? std::pow(10.0, t) : t, 4) + "</text>";
  }
  svg += "<text x=\"" + Num(kLeftPx + plot_w / 2) + "\" y=\"" + std::to_string(height_ - 6) +
         "\" text-anchor=\"middle\">" + EscapeHtml(x_label_) + "</text>";
  svg += "<text transform=\"translate(12," + Num(kTopPx + plot_h / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">" + EscapeHtml(y_label_) + "</text>";
  svg += "<svg x=\"" + std::to_string(kLeftPx) + "\" y=\"" + std::to_string(kTopPx) +
         "\" width=\"" + Num(plot_w) + "\" height=\"" + Num(plot_h) + "\" viewBox=\"" +
         std::to_string(kLeftPx) + " " + std::to_string(kTopPx) + " " + Num(plot_w) + " " +
         Num(plot_h) + "\" overflow=\"hidden\">";
  return svg;
}

// A point that can be drawn: finite, and positive on a log axis.
bool SvgPlot::Drawable(double x, double y) const {
  return std::isfinite(x) && std::isfinite(y) && (!log_x_ || x > 0) && (!log_y_ || y > 0);
}

// A polyline that lifts the pen over points it cannot draw.
std::string SvgPlot::RenderLine(const Item& item) const {
  std::string path;
  bool pen_down = false;
  for (std::size_t i = 0; i < item.x.size(); ++i) {
    if (!Drawable(item.x[i], item.y[i])) {
      pen_down = false;
      continue;
    }
    path += (pen_down ? "L" : "M") + Num(Tx(item.x[i])) + " " + Num(Ty(item.y[i]));
    pen_down = true;
  }
  return "<path d=\"" + path + "\" fill=\"none\" stroke=\"" + item.color + "\" stroke-width=\"" +
         Num(item.width) + "\"" +
         (item.dash.empty() ? "" : " stroke-dasharray=\"" + item.dash + "\"") + "/>";
}

// One polygon per run of drawable columns: along the maxima, back along the minima.
std::string SvgPlot::RenderBand(const Item& item) const {
  const auto drawable = [&](std::size_t k) {
    return Drawable(item.x[k], item.y[k]) && Drawable(item.x[k], item.y2[k]);
  };
  std::string svg;
  std::size_t i = 0;
  while (i < item.x.size()) {
    while (i < item.x.size() && !drawable(i)) ++i;
    std::size_t j = i;
    while (j < item.x.size() && drawable(j)) ++j;
    if (j > i) {
      std::string points;
      for (std::size_t k = i; k < j; ++k) {
        points += Num(Tx(item.x[k])) + "," + Num(Ty(item.y2[k])) + " ";
      }
      for (std::size_t k = j; k-- > i;) {
        points += Num(Tx(item.x[k])) + "," + Num(Ty(item.y[k])) + " ";
      }
      svg += "<polygon points=\"" + points + "\" fill=\"" + item.color + "\" stroke=\"" +
             item.color + "\" stroke-width=\"0.8\" fill-opacity=\"" + Num(item.width) +
             "\" stroke-opacity=\"" + Num(std::min(1.0, item.width + 0.3)) + "\"/>";
    }
    i = j;
  }
  return svg;
}

std::string SvgPlot::RenderMarkers(const Item& item) const {
  std::string svg;
  for (std::size_t i = 0; i < item.x.size(); ++i) {
    if (!Drawable(item.x[i], item.y[i])) continue;
    svg += "<circle cx=\"" + Num(Tx(item.x[i])) + "\" cy=\"" + Num(Ty(item.y[i])) + "\" r=\"" +
           Num(item.width) + "\" fill=\"" + item.color + "\"/>";
  }
  return svg;
}

std::string SvgPlot::RenderStems(const Item& item) const {
  std::string svg;
  for (std::size_t i = 0; i < item.x.size(); ++i) {
    if (!Drawable(item.x[i], item.y[i])) continue;
    svg += "<line x1=\"" + Num(Tx(item.x[i])) + "\" y1=\"" + Num(Ty(0.0)) + "\" x2=\"" +
           Num(Tx(item.x[i])) + "\" y2=\"" + Num(Ty(item.y[i])) + "\" stroke=\"" + item.color +
           "\" stroke-width=\"" + Num(item.width) + "\"/>";
  }
  return svg;
}

std::string SvgPlot::RenderLegend() const {
  std::string svg;
  double ly = kTopPx + 14;
  for (const auto& [label, color] : legend_) {
    const double lx = width_ - kRightPx - 210;
    svg += "<rect x=\"" + Num(lx) + "\" y=\"" + Num(ly - 9) +
           "\" width=\"12\" height=\"10\" fill=\"" + color + "\"/><text x=\"" + Num(lx + 16) +
           "\" y=\"" + Num(ly) + "\">" + EscapeHtml(label) + "</text>";
    ly += 14;
  }
  return svg;
}

}  // namespace mpdrig::report
