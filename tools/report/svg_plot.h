// A minimal inline-SVG line plot for the HTML report: axes with round-number ticks, lines,
// min/max bands, markers, horizontal reference lines. Coordinates are data values; NaN breaks a
// line. Output is plain SVG text (no script, no external reference), so the report stays one
// self-contained file.
#pragma once

#include <string>
#include <vector>

namespace mpdrig::report {

class SvgPlot {
 public:
  SvgPlot(int width_px, int height_px, std::string x_label, std::string y_label);

  void SetLogX(bool log_x) { log_x_ = log_x; }
  void SetLogY(bool log_y) { log_y_ = log_y; }
  // A line through (x[i], y[i]).
  void Line(const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
            double width_px = 1.2, const std::string& dash = "");
  // A filled band between lo and hi (a min/max envelope).
  void Band(const std::vector<double>& x, const std::vector<double>& lo,
            const std::vector<double>& hi, const std::string& color, double opacity);
  void Markers(const std::vector<double>& x, const std::vector<double>& y, const std::string& color,
               double radius_px = 2.5);
  void HorizontalLine(double y, const std::string& color, const std::string& dash = "4 3");
  // Vertical bars from 0 to y (stem plot, e.g. correlations).
  void Stems(const std::vector<double>& x, const std::vector<double>& y, const std::string& color);
  // Legend entries, drawn top right.
  void Legend(const std::string& label, const std::string& color);
  // Fixes the y range (otherwise the data's, with 5% margin).
  void SetYRange(double lo, double hi);

  std::string Render() const;

 private:
  struct Item {
    std::string kind;  // line, band, markers, hline, stems
    std::vector<double> x, y, y2;
    std::string color, dash;
    double width = 1.0;
  };
  double Tx(double x) const;
  double Ty(double y) const;
  void Extend(const std::vector<double>& x, const std::vector<double>& y);
  // Render's parts.
  double PlotWidth() const;
  double PlotHeight() const;
  void FixRanges() const;
  std::string RenderFrameAndAxes() const;
  bool Drawable(double x, double y) const;
  std::string RenderLine(const Item& item) const;
  std::string RenderBand(const Item& item) const;
  std::string RenderMarkers(const Item& item) const;
  std::string RenderStems(const Item& item) const;
  std::string RenderLegend() const;

  int width_, height_;
  std::string x_label_, y_label_;
  bool log_x_ = false, log_y_ = false;
  std::vector<Item> items_;
  std::vector<std::pair<std::string, std::string>> legend_;
  double x_lo_, x_hi_, y_lo_, y_hi_;
  bool y_fixed_ = false;
  // Set by Render from the data ranges.
  mutable double rx_lo_ = 0, rx_hi_ = 1, ry_lo_ = 0, ry_hi_ = 1;
};

// "1.23", "0.000123" -> "1.23e-4": 4 significant digits, for tables and labels.
std::string FormatValue(double value, int digits = 4);
// Escapes <, >, &, " for HTML text and attributes.
std::string EscapeHtml(const std::string& text);

}  // namespace mpdrig::report
