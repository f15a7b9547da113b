// SvgPlot (tools/report/svg_plot.h): the axes stay sane whatever range the data spans.
#include "tools/report/svg_plot.h"

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig::report {
namespace {

std::size_t Count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++n;
  }
  return n;
}

// A replayed input that is constant but for rounding (5 L/min and the next double up, as the
// pump's reconstruction gives on a noise-free log) once made the tick loop step by less than the
// values' own resolution: it never ended and ran out of memory (`mpdrig compare --report`
// aborted). Such a range is drawn as the point it is, with a handful of ticks.
TEST(SvgPlot, ARangeWithinRoundingIsDrawnAsAPointWithAFewTicks) {
  for (const double level : {5.0, 31.0, 101325.0, -2.5, 1e-9}) {
    SvgPlot plot(600, 200, "time [s]", "value");
    const double next = std::nextafter(level, std::numeric_limits<double>::infinity());
    plot.Line({0.0, 1.0, 2.0}, {level, next, level}, "#000");
    const std::string svg = plot.Render();
    // The 2 axis labels, at most 9 x ticks (0..2 in steps of 0.25) and a few y ticks.
    const std::size_t labels = Count(svg, "<text");
    EXPECT_GE(labels, 2u + 3u + 1u) << level;
    EXPECT_LE(labels, 2u + 9u + 12u) << level;
    EXPECT_NE(svg.find("<path d=\"M"), std::string::npos) << level;
  }
}

TEST(SvgPlot, AnExactPointAndAnEmptyPlotRenderToo) {
  SvgPlot point(600, 200, "x", "y");
  point.Markers({1.0}, {3.0}, "#000");
  EXPECT_NE(point.Render().find("<circle"), std::string::npos);
  SvgPlot empty(600, 200, "x", "y");
  EXPECT_EQ(empty.Render().rfind("</svg>"), empty.Render().size() - 6);
}

}  // namespace
}  // namespace mpdrig::report
