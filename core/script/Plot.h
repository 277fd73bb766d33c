#pragma once
// Line plots for scripts (loom.plot): an SVG written as text and a PNG rasterised here (lines,
// markers, a built-in 5x7 bitmap font), both from one layout: title, axis labels, linear or
// log ticks, grid, one colour and marker per series, legend in the emptiest corner.
#include <string>
#include <utility>
#include <vector>

#include "core/image/Image.h"

namespace loom::script {

struct PlotSeries {
    std::string name;
    std::vector<double> x, y;
};

struct PlotSpec {
    std::string title, xLabel, yLabel;
    bool logX = false, logY = false;
    std::vector<PlotSeries> series;
    uint32_t width = 800, height = 520;  // PNG pixels (SVG user units)
};

std::string plotSvg(const PlotSpec& spec);
ImageData plotImage(const PlotSpec& spec);
// Writes STEM.svg and STEM.png, where STEM is `path` without a .svg/.png extension; creates
// parent directories. Returns {svg path, png path}. Throws UserError on empty/invalid data.
std::pair<std::string, std::string> writePlot(const std::string& path, const PlotSpec& spec);

}  // namespace loom::script
