#include "core/script/Plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/util/Error.h"
#include "core/util/Log.h"
#include "core/util/AtomicFile.h"

namespace loom::script {

namespace {

// ---------------------------------------------------------------------------------------------
// A 5x7 bitmap font for ASCII 32..126: five columns per glyph, bit 0 = top row (the classic
// HD44780-style layout), rows 0..6 with the baseline on row 6; g, j, p, q, y are redrawn with
// descenders on rows 7..8 (kDescenders). Glyph cells advance 6 columns.
constexpr uint16_t kFont[95][5] = {
    {0x00, 0x00, 0x00, 0x00, 0x00}, {0x00, 0x00, 0x5F, 0x00, 0x00},  // space !
    {0x00, 0x07, 0x00, 0x07, 0x00}, {0x14, 0x7F, 0x14, 0x7F, 0x14},  // " #
    {0x24, 0x2A, 0x7F, 0x2A, 0x12}, {0x23, 0x13, 0x08, 0x64, 0x62},  // $ %
    {0x36, 0x49, 0x55, 0x22, 0x50}, {0x00, 0x05, 0x03, 0x00, 0x00},  // & '
    {0x00, 0x1C, 0x22, 0x41, 0x00}, {0x00, 0x41, 0x22, 0x1C, 0x00},  // ( )
    {0x14, 0x08, 0x3E, 0x08, 0x14}, {0x08, 0x08, 0x3E, 0x08, 0x08},  // * +
    {0x00, 0x50, 0x30, 0x00, 0x00}, {0x08, 0x08, 0x08, 0x08, 0x08},  // , -
    {0x00, 0x60, 0x60, 0x00, 0x00}, {0x20, 0x10, 0x08, 0x04, 0x02},  // . /
    {0x3E, 0x51, 0x49, 0x45, 0x3E}, {0x00, 0x42, 0x7F, 0x40, 0x00},  // 0 1
    {0x42, 0x61, 0x51, 0x49, 0x46}, {0x21, 0x41, 0x45, 0x4B, 0x31},  // 2 3
    {0x18, 0x14, 0x12, 0x7F, 0x10}, {0x27, 0x45, 0x45, 0x45, 0x39},  // 4 5
    {0x3C, 0x4A, 0x49, 0x49, 0x30}, {0x01, 0x71, 0x09, 0x05, 0x03},  // 6 7
    {0x36, 0x49, 0x49, 0x49, 0x36}, {0x06, 0x49, 0x49, 0x29, 0x1E},  // 8 9
    {0x00, 0x36, 0x36, 0x00, 0x00}, {0x00, 0x56, 0x36, 0x00, 0x00},  // : ;
    {0x08, 0x14, 0x22, 0x41, 0x00}, {0x14, 0x14, 0x14, 0x14, 0x14},  // < =
    {0x00, 0x41, 0x22, 0x14, 0x08}, {0x02, 0x01, 0x51, 0x09, 0x06},  // > ?
    {0x32, 0x49, 0x79, 0x41, 0x3E}, {0x7E, 0x11, 0x11, 0x11, 0x7E},  // @ A
    {0x7F, 0x49, 0x49, 0x49, 0x36}, {0x3E, 0x41, 0x41, 0x41, 0x22},  // B C
    {0x7F, 0x41, 0x41, 0x22, 0x1C}, {0x7F, 0x49, 0x49, 0x49, 0x41},  // D E
    {0x7F, 0x09, 0x09, 0x09, 0x01}, {0x3E, 0x41, 0x49, 0x49, 0x7A},  // F G
    {0x7F, 0x08, 0x08, 0x08, 0x7F}, {0x00, 0x41, 0x7F, 0x41, 0x00},  // H I
    {0x20, 0x40, 0x41, 0x3F, 0x01}, {0x7F, 0x08, 0x14, 0x22, 0x41},  // J K
    {0x7F, 0x40, 0x40, 0x40, 0x40}, {0x7F, 0x02, 0x0C, 0x02, 0x7F},  // L M
    {0x7F, 0x04, 0x08, 0x10, 0x7F}, {0x3E, 0x41, 0x41, 0x41, 0x3E},  // N O
    {0x7F, 0x09, 0x09, 0x09, 0x06}, {0x3E, 0x41, 0x51, 0x21, 0x5E},  // P Q
    {0x7F, 0x09, 0x19, 0x29, 0x46}, {0x46, 0x49, 0x49, 0x49, 0x31},  // R S
    {0x01, 0x01, 0x7F, 0x01, 0x01}, {0x3F, 0x40, 0x40, 0x40, 0x3F},  // T U
    {0x1F, 0x20, 0x40, 0x20, 0x1F}, {0x3F, 0x40, 0x38, 0x40, 0x3F},  // V W
    {0x63, 0x14, 0x08, 0x14, 0x63}, {0x07, 0x08, 0x70, 0x08, 0x07},  // X Y
    {0x61, 0x51, 0x49, 0x45, 0x43}, {0x00, 0x7F, 0x41, 0x41, 0x00},  // Z [
    {0x02, 0x04, 0x08, 0x10, 0x20}, {0x00, 0x41, 0x41, 0x7F, 0x00},  // \ ]
    {0x04, 0x02, 0x01, 0x02, 0x04}, {0x40, 0x40, 0x40, 0x40, 0x40},  // ^ _
    {0x00, 0x01, 0x02, 0x04, 0x00}, {0x20, 0x54, 0x54, 0x54, 0x78},  // ` a
    {0x7F, 0x48, 0x44, 0x44, 0x38}, {0x38, 0x44, 0x44, 0x44, 0x20},  // b c
    {0x38, 0x44, 0x44, 0x48, 0x7F}, {0x38, 0x54, 0x54, 0x54, 0x18},  // d e
    {0x08, 0x7E, 0x09, 0x01, 0x02}, {0x0C, 0x52, 0x52, 0x52, 0x3E},  // f g
    {0x7F, 0x08, 0x04, 0x04, 0x78}, {0x00, 0x44, 0x7D, 0x40, 0x00},  // h i
    {0x20, 0x40, 0x44, 0x3D, 0x00}, {0x7F, 0x10, 0x28, 0x44, 0x00},  // j k
    {0x00, 0x41, 0x7F, 0x40, 0x00}, {0x7C, 0x04, 0x18, 0x04, 0x78},  // l m
    {0x7C, 0x08, 0x04, 0x04, 0x78}, {0x38, 0x44, 0x44, 0x44, 0x38},  // n o
    {0x7C, 0x14, 0x14, 0x14, 0x08}, {0x08, 0x14, 0x14, 0x18, 0x7C},  // p q
    {0x7C, 0x08, 0x04, 0x04, 0x08}, {0x48, 0x54, 0x54, 0x54, 0x20},  // r s
    {0x04, 0x3F, 0x44, 0x40, 0x20}, {0x3C, 0x40, 0x40, 0x20, 0x7C},  // t u
    {0x1C, 0x20, 0x40, 0x20, 0x1C}, {0x3C, 0x40, 0x30, 0x40, 0x3C},  // v w
    {0x44, 0x28, 0x10, 0x28, 0x44}, {0x0C, 0x50, 0x50, 0x50, 0x3C},  // x y
    {0x44, 0x64, 0x54, 0x4C, 0x44}, {0x00, 0x08, 0x36, 0x41, 0x00},  // z {
    {0x00, 0x00, 0x7F, 0x00, 0x00}, {0x00, 0x41, 0x36, 0x08, 0x00},  // | }
    {0x08, 0x04, 0x08, 0x10, 0x08},                                  // ~
};

struct Descender {
    char c;
    uint16_t columns[5];
};
constexpr Descender kDescenders[] = {{'g', {0x118, 0x124, 0x124, 0x124, 0x0FC}},
                                     {'j', {0x080, 0x100, 0x100, 0x0FD, 0x000}},
                                     {'p', {0x1FC, 0x024, 0x024, 0x024, 0x018}},
                                     {'q', {0x018, 0x024, 0x024, 0x024, 0x1FC}},
                                     {'y', {0x11C, 0x120, 0x120, 0x120, 0x0FC}}};

const uint16_t* glyph(unsigned char ch) {
    for (const auto& d : kDescenders)
        if (d.c == char(ch)) return d.columns;
    return kFont[(ch >= 32 && ch <= 126 ? ch : '?') - 32];
}

constexpr int kGlyphAdvance = 6, kGlyphHeight = 7, kGlyphRows = 9;

// Tableau 10: distinct and colour-blind friendlier than the primaries.
constexpr std::array<uint32_t, 10> kPalette = {0x4e79a7, 0xf28e2b, 0xe15759, 0x59a14f, 0xb07aa1,
                                               0x76b7b2, 0xedc948, 0xff9da7, 0x9c755f, 0xbab0ac};
enum class MarkerShape { Circle, Square, Diamond, Triangle };

struct Color {
    float r, g, b;
    static Color hex(uint32_t v) {
        return {float((v >> 16) & 0xff) / 255.0f, float((v >> 8) & 0xff) / 255.0f,
                float(v & 0xff) / 255.0f};
    }
    std::string svg() const {
        return fmt::format("#{:02x}{:02x}{:02x}", int(std::lround(r * 255)),
                           int(std::lround(g * 255)), int(std::lround(b * 255)));
    }
};

// ---------------------------------------------------------------------------------------------
// One display list drives both outputs, so the SVG and the PNG show the same plot.
struct Item {
    enum class Kind { Rect, Polyline, Marker, Text } kind;
    std::vector<std::pair<double, double>> points;  // Rect: two corners; Polyline; Marker/Text: one
    Color color{0, 0, 0};
    bool filled = false;  // Rect
    Color fill{1, 1, 1};
    double width = 1.0;  // stroke width; Marker: radius; Text: font scale
    MarkerShape shape = MarkerShape::Circle;
    std::string text;
    int anchor = 0;  // Text: -1 start, 0 middle, 1 end
    bool vertical = false;
};

struct Axis {
    double lo = 0, hi = 1;  // data range shown, in transformed units (log10 when log)
    bool log = false;
    std::vector<double> major, minor;  // tick positions in transformed units
    std::vector<std::string> labels;
};

std::string compactNumber(double v) {
    std::string s = fmt::format("{:g}", v);
    // 1e+05 -> 1e5, 1e-05 -> 1e-5
    auto e = s.find('e');
    if (e != std::string::npos) {
        std::string mant = s.substr(0, e), exp = s.substr(e + 1);
        bool neg = exp[0] == '-';
        if (exp[0] == '+' || exp[0] == '-') exp = exp.substr(1);
        exp.erase(0, std::min(exp.find_first_not_of('0'), exp.size() - 1));
        s = mant + "e" + (neg ? "-" : "") + exp;
    }
    return s;
}

std::string linearLabel(double v, double step) {
    if (std::fabs(v) < step * 1e-6) return "0";
    if (std::fabs(v) >= 1e5 || step < 1e-4) return compactNumber(v);
    int decimals = std::max(0, int(-std::floor(std::log10(step) + 1e-9)));
    return fmt::format("{:.{}f}", v, decimals);
}

double niceStep(double range, int target) {
    double raw = range / std::max(target, 1);
    double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double f = raw / mag;
    double nice = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
    return nice * mag;
}

void linearTicks(Axis& a, double lo, double hi, bool valuesAreLog) {
    // lo/hi in value space; positions stored in transformed space.
    double step = niceStep(hi - lo, 6);
    for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) {
        double pos = valuesAreLog ? std::log10(v) : v;
        if (valuesAreLog && !(v > 0)) continue;
        a.major.push_back(pos);
        a.labels.push_back(linearLabel(v, step));
    }
}

Axis makeAxis(std::vector<double> values, bool log) {
    Axis a;
    a.log = log;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (double v : values) {
        double t = log ? std::log10(v) : v;
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    if (hi - lo < 1e-12 * std::max(1.0, std::fabs(hi))) {
        double pad = log ? 0.5 : std::max(std::fabs(hi) * 0.1, 1.0);
        lo -= pad;
        hi += pad;
    }
    double pad = 0.05 * (hi - lo);
    a.lo = lo - pad;
    a.hi = hi + pad;
    if (!log) {
        linearTicks(a, a.lo, a.hi, false);
        return a;
    }
    // Decades; every k-th decade when there are many; 1-2-5 when there are too few.
    int d0 = int(std::ceil(a.lo - 1e-9)), d1 = int(std::floor(a.hi + 1e-9));
    int decades = d1 - d0 + 1;
    if (decades >= 3) {
        int every = std::max(1, int(std::ceil(decades / 8.0)));
        for (int k = d0; k <= d1; ++k) {
            if ((k - d0) % every) continue;
            a.major.push_back(k);
            a.labels.push_back(k >= -3 && k <= 4 ? compactNumber(std::pow(10.0, k))
                                                 : fmt::format("1e{}", k));
        }
        if (every == 1)
            for (int k = d0 - 1; k <= d1; ++k)
                for (int m = 2; m <= 9; ++m) {
                    double t = k + std::log10(double(m));
                    if (t > a.lo && t < a.hi) a.minor.push_back(t);
                }
        return a;
    }
    for (int k = d0 - 1; k <= d1 + 1; ++k)
        for (int m = 1; m <= 9; ++m) {
            double t = k + std::log10(double(m));
            if (t < a.lo || t > a.hi) continue;
            if (m == 1 || m == 2 || m == 5) {
                a.major.push_back(t);
                a.labels.push_back(compactNumber(m * std::pow(10.0, k)));
            } else {
                a.minor.push_back(t);
            }
        }
    if (a.major.size() < 3) {
        a.major.clear();
        a.minor.clear();
        a.labels.clear();
        linearTicks(a, std::pow(10.0, a.lo), std::pow(10.0, a.hi), true);
    }
    return a;
}

double textWidth(const std::string& s, double scale) {
    return s.empty() ? 0.0 : (kGlyphAdvance * double(s.size()) - 1.0) * scale;
}

bool usable(double v, bool log) {
    return std::isfinite(v) && (!log || v > 0);
}

std::vector<Item> layout(const PlotSpec& spec) {
    if (spec.width < 200 || spec.height < 150)
        throw UserError("plot: size must be at least 200x150");
    std::vector<double> xs, ys;
    for (auto& s : spec.series) {
        if (s.x.size() != s.y.size())
            throw UserError(fmt::format("plot: series '{}' has {} x values but {} y values", s.name,
                                        s.x.size(), s.y.size()));
        for (size_t i = 0; i < s.x.size(); ++i)
            if (usable(s.x[i], spec.logX) && usable(s.y[i], spec.logY)) {
                xs.push_back(s.x[i]);
                ys.push_back(s.y[i]);
            }
    }
    if (xs.empty())
        throw UserError(std::string("plot: no data point to draw (") +
                        (spec.series.empty() ? "no series" : "every value is non-finite") +
                        (spec.logX || spec.logY ? " or not positive on a log axis" : "") + ")");
    Axis ax = makeAxis(xs, spec.logX), ay = makeAxis(ys, spec.logY);

    const double W = spec.width, H = spec.height;
    const double tickScale = 2, labelScale = 2;
    const Color ink = Color::hex(0x222222), grid = Color::hex(0xdddddd),
                minorGrid = Color::hex(0xf0f0f0);
    double maxTick = 0;
    for (auto& l : ay.labels) maxTick = std::max(maxTick, textWidth(l, tickScale));
    double left = 16 + (spec.yLabel.empty() ? 0 : kGlyphHeight * labelScale + 14) + maxTick + 12;
    // The title is centred over the plot area: the largest whole glyph scale (at most 3) that
    // keeps it inside the image.
    double titleScale = 3;
    if (!spec.title.empty()) {
        double cx = (left + W - 28) / 2, room = 2 * std::min(cx, W - cx) - 16;
        titleScale = std::clamp(std::floor(room / textWidth(spec.title, 1.0)), 1.0, 3.0);
    }
    double top = spec.title.empty() ? 20 : 20 + kGlyphHeight * titleScale + 16;
    double bottom = H - (12 + kGlyphHeight * tickScale + 8 +
                         (spec.xLabel.empty() ? 0 : kGlyphHeight * labelScale + 12) + 12);
    double right = W - 28;
    auto px = [&](double v) {
        double t = ax.log ? std::log10(v) : v;
        return left + (t - ax.lo) / (ax.hi - ax.lo) * (right - left);
    };
    auto py = [&](double v) {
        double t = ay.log ? std::log10(v) : v;
        return bottom - (t - ay.lo) / (ay.hi - ay.lo) * (bottom - top);
    };
    auto pxT = [&](double t) { return left + (t - ax.lo) / (ax.hi - ax.lo) * (right - left); };
    auto pyT = [&](double t) { return bottom - (t - ay.lo) / (ay.hi - ay.lo) * (bottom - top); };

    std::vector<Item> items;
    auto line = [&](double x0, double y0, double x1, double y1, Color c, double w) {
        Item it{Item::Kind::Polyline};
        it.points = {{x0, y0}, {x1, y1}};
        it.color = c;
        it.width = w;
        items.push_back(it);
    };
    auto text = [&](double x, double y, std::string s, double scale, int anchor,
                    bool vertical = false) {
        Item it{Item::Kind::Text};
        it.points = {{x, y}};
        it.text = std::move(s);
        it.width = scale;
        it.anchor = anchor;
        it.vertical = vertical;
        it.color = ink;
        items.push_back(it);
    };

    // Background, grid, frame, ticks and labels.
    Item bg{Item::Kind::Rect};
    bg.points = {{0, 0}, {W, H}};
    bg.filled = true;
    bg.fill = Color::hex(0xffffff);
    bg.width = 0;
    items.push_back(bg);
    for (double t : ax.minor) line(pxT(t), top, pxT(t), bottom, minorGrid, 1);
    for (double t : ay.minor) line(left, pyT(t), right, pyT(t), minorGrid, 1);
    for (double t : ax.major) line(pxT(t), top, pxT(t), bottom, grid, 1);
    for (double t : ay.major) line(left, pyT(t), right, pyT(t), grid, 1);
    Item frame{Item::Kind::Rect};
    frame.points = {{left, top}, {right, bottom}};
    frame.color = Color::hex(0x333333);
    frame.width = 1.5;
    items.push_back(frame);
    for (size_t i = 0; i < ax.major.size(); ++i) {
        double x = pxT(ax.major[i]);
        line(x, bottom, x, bottom + 6, ink, 1.5);
        text(x, bottom + 12 + kGlyphHeight * tickScale / 2, ax.labels[i], tickScale, 0);
    }
    for (size_t i = 0; i < ay.major.size(); ++i) {
        double y = pyT(ay.major[i]);
        line(left - 6, y, left, y, ink, 1.5);
        text(left - 10, y, ay.labels[i], tickScale, 1);
    }
    if (!spec.title.empty())
        text((left + right) / 2, 20 + kGlyphHeight * titleScale / 2, spec.title, titleScale, 0);
    if (!spec.xLabel.empty())
        text((left + right) / 2, H - 12 - kGlyphHeight * labelScale / 2, spec.xLabel, labelScale,
             0);
    if (!spec.yLabel.empty())
        text(16 + kGlyphHeight * labelScale / 2, (top + bottom) / 2, spec.yLabel, labelScale, 0,
             true);

    // Series: lines broken at unusable points, markers on every point.
    std::vector<std::pair<double, double>> drawn;  // for legend placement
    for (size_t si = 0; si < spec.series.size(); ++si) {
        const auto& s = spec.series[si];
        Color c = Color::hex(kPalette[si % kPalette.size()]);
        auto shape = MarkerShape(si % 4);
        Item poly{Item::Kind::Polyline};
        poly.color = c;
        poly.width = 2.5;
        auto flush = [&] {
            if (poly.points.size() >= 2) items.push_back(poly);
            poly.points.clear();
        };
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!usable(s.x[i], spec.logX) || !usable(s.y[i], spec.logY)) {
                flush();
                continue;
            }
            poly.points.push_back({px(s.x[i]), py(s.y[i])});
            drawn.push_back(poly.points.back());
            if (poly.points.size() >= 2) {  // sample segments too, so the legend avoids them
                auto [x0, y0] = poly.points[poly.points.size() - 2];
                for (int k = 1; k < 8; ++k)
                    drawn.push_back(
                        {x0 + (px(s.x[i]) - x0) * k / 8, y0 + (py(s.y[i]) - y0) * k / 8});
            }
        }
        flush();
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!usable(s.x[i], spec.logX) || !usable(s.y[i], spec.logY)) continue;
            Item m{Item::Kind::Marker};
            m.points = {{px(s.x[i]), py(s.y[i])}};
            m.color = c;
            m.width = 4.5;
            m.shape = shape;
            items.push_back(m);
        }
    }

    // Legend in the corner that covers the fewest drawn points.
    std::vector<size_t> named;
    double maxName = 0;
    for (size_t si = 0; si < spec.series.size(); ++si)
        if (!spec.series[si].name.empty()) {
            named.push_back(si);
            maxName = std::max(maxName, textWidth(spec.series[si].name, labelScale));
        }
    if (!named.empty()) {
        double rowH = kGlyphHeight * labelScale + 10;
        double lw = 12 + 36 + 10 + maxName + 12, lh = rowH * double(named.size()) + 10;
        double pad = 10;
        std::array<std::pair<double, double>, 4> corners = {
            std::pair{right - pad - lw, top + pad}, std::pair{left + pad, top + pad},
            std::pair{right - pad - lw, bottom - pad - lh},
            std::pair{left + pad, bottom - pad - lh}};
        size_t best = 0, bestCount = SIZE_MAX;
        for (size_t c = 0; c < corners.size(); ++c) {
            auto [x0, y0] = corners[c];
            size_t n = 0;
            for (auto [x, y] : drawn)
                if (x >= x0 - 6 && x <= x0 + lw + 6 && y >= y0 - 6 && y <= y0 + lh + 6) ++n;
            if (n < bestCount) {
                best = c;
                bestCount = n;
            }
        }
        auto [x0, y0] = corners[best];
        Item box{Item::Kind::Rect};
        box.points = {{x0, y0}, {x0 + lw, y0 + lh}};
        box.filled = true;
        box.fill = Color::hex(0xffffff);
        box.color = Color::hex(0x999999);
        box.width = 1;
        items.push_back(box);
        for (size_t k = 0; k < named.size(); ++k) {
            size_t si = named[k];
            Color c = Color::hex(kPalette[si % kPalette.size()]);
            double y = y0 + 5 + rowH * (double(k) + 0.5);
            line(x0 + 12, y, x0 + 48, y, c, 2.5);
            Item m{Item::Kind::Marker};
            m.points = {{x0 + 30, y}};
            m.color = c;
            m.width = 4.5;
            m.shape = MarkerShape(si % 4);
            items.push_back(m);
            text(x0 + 58, y, spec.series[si].name, labelScale, -1);
        }
    }
    return items;
}

// ---------------------------------------------------------------------------------------------
// SVG

std::string xmlEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
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

std::string markerSvg(const Item& m) {
    auto [x, y] = m.points[0];
    double r = m.width;
    std::string fill = m.color.svg();
    switch (m.shape) {
        case MarkerShape::Circle:
            return fmt::format("<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"{:.2f}\" fill=\"{}\"/>\n",
                               x, y, r, fill);
        case MarkerShape::Square:
            return fmt::format(
                "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" "
                "fill=\"{}\"/>\n",
                x - r * 0.85, y - r * 0.85, r * 1.7, r * 1.7, fill);
        case MarkerShape::Diamond:
            return fmt::format(
                "<polygon points=\"{:.2f},{:.2f} {:.2f},{:.2f} {:.2f},{:.2f} {:.2f},{:.2f}\" "
                "fill=\"{}\"/>\n",
                x, y - r * 1.2, x + r * 1.2, y, x, y + r * 1.2, x - r * 1.2, y, fill);
        case MarkerShape::Triangle:
            return fmt::format(
                "<polygon points=\"{:.2f},{:.2f} {:.2f},{:.2f} {:.2f},{:.2f}\" fill=\"{}\"/>\n", x,
                y - r * 1.2, x + r * 1.1, y + r * 0.8, x - r * 1.1, y + r * 0.8, fill);
    }
    return "";
}

// ---------------------------------------------------------------------------------------------
// Raster: drawn at kSuper x resolution and box-filtered down (anti-aliasing).

constexpr int kSuper = 3;

class Canvas {
public:
    Canvas(uint32_t w, uint32_t h)
        : mW(int(w) * kSuper), mH(int(h) * kSuper), mRgb(size_t(mW) * mH * 3, 1.0f) {}

    void blend(int x, int y, Color c, float a) {
        if (x < 0 || y < 0 || x >= mW || y >= mH || a <= 0) return;
        float* p = &mRgb[(size_t(y) * mW + x) * 3];
        a = std::min(a, 1.0f);
        p[0] += (c.r - p[0]) * a;
        p[1] += (c.g - p[1]) * a;
        p[2] += (c.b - p[2]) * a;
    }
    // Coordinates in output pixels; converted to the supersampled grid here.
    void fillRect(double x0, double y0, double x1, double y1, Color c) {
        for (int y = int(std::floor(y0 * kSuper)); y < int(std::ceil(y1 * kSuper)); ++y)
            for (int x = int(std::floor(x0 * kSuper)); x < int(std::ceil(x1 * kSuper)); ++x)
                blend(x, y, c, 1.0f);
    }
    void segment(double x0, double y0, double x1, double y1, double width, Color c) {
        x0 *= kSuper, y0 *= kSuper, x1 *= kSuper, y1 *= kSuper;
        double hw = std::max(width * kSuper * 0.5, 0.5);
        int bx0 = int(std::floor(std::min(x0, x1) - hw - 1)),
            bx1 = int(std::ceil(std::max(x0, x1) + hw + 1));
        int by0 = int(std::floor(std::min(y0, y1) - hw - 1)),
            by1 = int(std::ceil(std::max(y0, y1) + hw + 1));
        double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
        for (int y = std::max(by0, 0); y <= std::min(by1, mH - 1); ++y)
            for (int x = std::max(bx0, 0); x <= std::min(bx1, mW - 1); ++x) {
                double cx = x + 0.5, cy = y + 0.5;
                double t =
                    len2 > 0 ? std::clamp(((cx - x0) * dx + (cy - y0) * dy) / len2, 0.0, 1.0) : 0.0;
                double ex = cx - (x0 + t * dx), ey = cy - (y0 + t * dy);
                double d = std::sqrt(ex * ex + ey * ey);
                blend(x, y, c, float(std::clamp(hw + 0.5 - d, 0.0, 1.0)));
            }
    }
    void marker(double x, double y, double r, MarkerShape shape, Color c) {
        x *= kSuper, y *= kSuper, r *= kSuper;
        for (int py = int(y - 2 * r); py <= int(y + 2 * r); ++py)
            for (int px = int(x - 2 * r); px <= int(x + 2 * r); ++px) {
                double dx = px + 0.5 - x, dy = py + 0.5 - y;
                bool in = false;
                switch (shape) {
                    case MarkerShape::Circle:
                        in = dx * dx + dy * dy <= r * r;
                        break;
                    case MarkerShape::Square:
                        in = std::fabs(dx) <= r * 0.85 && std::fabs(dy) <= r * 0.85;
                        break;
                    case MarkerShape::Diamond:
                        in = std::fabs(dx) + std::fabs(dy) <= r * 1.2;
                        break;
                    case MarkerShape::Triangle:
                        // Apex (0, -1.2r), base y = +0.8r, half-width 1.1r.
                        in = dy <= r * 0.8 && dy >= -r * 1.2 &&
                             std::fabs(dx) <= 1.1 * r * (dy + r * 1.2) / (2.0 * r);
                        break;
                }
                if (in) blend(px, py, c, 1.0f);
            }
    }
    void text(double x, double y, const std::string& s, double scale, int anchor, bool vertical,
              Color c) {
        double w = textWidth(s, scale), h = kGlyphHeight * scale;
        // Along-text offset of the first glyph relative to the anchor; text is centred on y.
        double start = anchor < 0 ? 0.0 : anchor == 0 ? -w / 2 : -w;
        for (size_t i = 0; i < s.size(); ++i) {
            const uint16_t* columns = glyph(static_cast<unsigned char>(s[i]));
            for (int col = 0; col < 5; ++col)
                for (int row = 0; row < kGlyphRows; ++row) {
                    if (!(columns[col] >> row & 1)) continue;
                    double u = start + (double(i) * kGlyphAdvance + col) * scale;  // along text
                    double v = -h / 2 + row * scale;                               // across text
                    if (!vertical)
                        fillRect(x + u, y + v, x + u + scale, y + v + scale, c);
                    else  // rotated 90 degrees counter-clockwise: reads bottom to top
                        fillRect(x + v, y - u - scale, x + v + scale, y - u, c);
                }
        }
    }
    ImageData resolve() const {
        uint32_t w = uint32_t(mW / kSuper), h = uint32_t(mH / kSuper);
        ImageData out = ImageData::make(w, h, 4, 1.0f);
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    float sum = 0;
                    for (int sy = 0; sy < kSuper; ++sy)
                        for (int sx = 0; sx < kSuper; ++sx)
                            sum += mRgb[((size_t(y) * kSuper + sy) * mW + x * kSuper + sx) * 3 + c];
                    out.at(x, y, c) = sum / (kSuper * kSuper);
                }
        return out;
    }

private:
    int mW, mH;
    std::vector<float> mRgb;
};

}  // namespace

std::string plotSvg(const PlotSpec& spec) {
    std::vector<Item> items = layout(spec);
    std::string s = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" "
        "viewBox=\"0 0 {0} {1}\" font-family=\"DejaVu Sans Mono, Menlo, Consolas, monospace\">\n",
        spec.width, spec.height);
    if (!spec.title.empty()) s += "<title>" + xmlEscape(spec.title) + "</title>\n";
    for (const Item& it : items) {
        switch (it.kind) {
            case Item::Kind::Rect: {
                auto [x0, y0] = it.points[0];
                auto [x1, y1] = it.points[1];
                s += fmt::format(
                    "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" "
                    "fill=\"{}\"",
                    x0, y0, x1 - x0, y1 - y0, it.filled ? it.fill.svg() : "none");
                if (it.width > 0)
                    s +=
                        fmt::format(" stroke=\"{}\" stroke-width=\"{}\"", it.color.svg(), it.width);
                s += "/>\n";
                break;
            }
            case Item::Kind::Polyline: {
                s += fmt::format(
                    "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" "
                    "stroke-linejoin=\"round\" stroke-linecap=\"round\" points=\"",
                    it.color.svg(), it.width);
                for (size_t i = 0; i < it.points.size(); ++i)
                    s += fmt::format("{}{:.2f},{:.2f}", i ? " " : "", it.points[i].first,
                                     it.points[i].second);
                s += "\"/>\n";
                break;
            }
            case Item::Kind::Marker:
                s += markerSvg(it);
                break;
            case Item::Kind::Text: {
                auto [x, y] = it.points[0];
                // The bitmap font's cell is 6x7 units per scale: a 10-unit monospace em matches.
                s += fmt::format(
                    "<text x=\"{:.2f}\" y=\"{:.2f}\" font-size=\"{:.1f}\" fill=\"{}\" "
                    "text-anchor=\"{}\" dominant-baseline=\"central\"{}>{}</text>\n",
                    x, y, 10.0 * it.width, it.color.svg(),
                    it.anchor < 0    ? "start"
                    : it.anchor == 0 ? "middle"
                                     : "end",
                    it.vertical ? fmt::format(" transform=\"rotate(-90 {:.2f} {:.2f})\"", x, y)
                                : "",
                    xmlEscape(it.text));
                break;
            }
        }
    }
    return s + "</svg>\n";
}

ImageData plotImage(const PlotSpec& spec) {
    std::vector<Item> items = layout(spec);
    Canvas canvas(spec.width, spec.height);
    for (const Item& it : items) {
        switch (it.kind) {
            case Item::Kind::Rect: {
                auto [x0, y0] = it.points[0];
                auto [x1, y1] = it.points[1];
                if (it.filled) canvas.fillRect(x0, y0, x1, y1, it.fill);
                if (it.width > 0) {
                    canvas.segment(x0, y0, x1, y0, it.width, it.color);
                    canvas.segment(x1, y0, x1, y1, it.width, it.color);
                    canvas.segment(x1, y1, x0, y1, it.width, it.color);
                    canvas.segment(x0, y1, x0, y0, it.width, it.color);
                }
                break;
            }
            case Item::Kind::Polyline:
                for (size_t i = 1; i < it.points.size(); ++i)
                    canvas.segment(it.points[i - 1].first, it.points[i - 1].second,
                                   it.points[i].first, it.points[i].second, it.width, it.color);
                break;
            case Item::Kind::Marker:
                canvas.marker(it.points[0].first, it.points[0].second, it.width, it.shape,
                              it.color);
                break;
            case Item::Kind::Text:
                canvas.text(it.points[0].first, it.points[0].second, it.text, it.width, it.anchor,
                            it.vertical, it.color);
                break;
        }
    }
    return canvas.resolve();
}

std::pair<std::string, std::string> writePlot(const std::string& path, const PlotSpec& spec) {
    namespace fs = std::filesystem;
    if (path.empty()) throw UserError("plot: 'path' is empty");
    fs::path stem = path;
    std::string ext = stem.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".svg" || ext == ".png") stem.replace_extension();
    std::string svgPath = stem.string() + ".svg", pngPath = stem.string() + ".png";
    std::string svg = plotSvg(spec);  // validates before anything is written
    writeTextFileAtomic(svgPath, "plot", svg);
    writeImage(pngPath, plotImage(spec));
    return {svgPath, pngPath};
}

}  // namespace loom::script
