// FLIP (Andersson et al. 2020) and HDR-FLIP (Andersson et al. 2021), from the papers' formulas:
// Sec. 4 (colour pipeline: CSF filters as sums of Gaussians in YCxCz, clamp to the RGB cube,
// Hunt-adjusted L*a*b*, HyAB, the error redistribution with q_c = 0.7, p_c = 0.4, p_t = 0.95),
// Sec. 5 (feature pipeline: first and second Gaussian derivatives of width 0.082 degrees on the
// achromatic channel, q_f = 0.5) and Eq. 8 (error = colour^(1 - feature)); HDR-FLIP Sec. 3
// (exposure range from the ACES curve, per-pixel maximum over exposures).
#include "core/image/Flip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/util/Error.h"  // UserError

namespace loom {

namespace {

using Vec3 = std::array<double, 3>;
constexpr Vec3 kWhiteD65 = {0.950428545, 1.0, 1.088900371};

double srgbToLinear(double v) {
    return v > 0.04045 ? std::pow((v + 0.055) / 1.055, 2.4) : v / 12.92;
}
// Negative and NaN values count as 0 (+inf stays: the tone curve maps it to 1).
double nonNegative(double v) {
    return v > 0.0 ? v : 0.0;
}

// Linear sRGB (D65) <-> CIE XYZ.
Vec3 linearToXyz(const Vec3& c) {
    return {0.4123908 * c[0] + 0.3575843 * c[1] + 0.1804808 * c[2],
            0.2126390 * c[0] + 0.7151687 * c[1] + 0.0721923 * c[2],
            0.0193308 * c[0] + 0.1191948 * c[1] + 0.9505322 * c[2]};
}
Vec3 xyzToLinear(const Vec3& c) {
    return {3.2409699 * c[0] - 1.5373832 * c[1] - 0.4986108 * c[2],
            -0.9692436 * c[0] + 1.8759675 * c[1] + 0.0415551 * c[2],
            0.0556301 * c[0] - 0.2039770 * c[1] + 1.0569715 * c[2]};
}

// YCxCz: the linear opponent space of the CSF filtering.
Vec3 xyzToYcxcz(const Vec3& c) {
    double x = c[0] / kWhiteD65[0], y = c[1] / kWhiteD65[1], z = c[2] / kWhiteD65[2];
    return {116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)};
}
Vec3 ycxczToXyz(const Vec3& c) {
    double y = (c[0] + 16.0) / 116.0;
    return {(y + c[1] / 500.0) * kWhiteD65[0], y * kWhiteD65[1], (y - c[2] / 200.0) * kWhiteD65[2]};
}

// CIE L*a*b* with the Hunt adjustment (chroma scaled by 0.01 L*).
Vec3 linearToHuntLab(const Vec3& rgb) {
    Vec3 xyz = linearToXyz(rgb);
    constexpr double d = 6.0 / 29.0;
    auto f = [&](double t) {
        return t > d * d * d ? std::cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
    };
    double fx = f(xyz[0] / kWhiteD65[0]), fy = f(xyz[1] / kWhiteD65[1]),
           fz = f(xyz[2] / kWhiteD65[2]);
    double L = 116.0 * fy - 16.0;
    return {L, 0.01 * L * 500.0 * (fx - fy), 0.01 * L * 200.0 * (fy - fz)};
}

double hyab(const Vec3& a, const Vec3& b) {
    return std::abs(a[0] - b[0]) + std::hypot(a[1] - b[1], a[2] - b[2]);
}

struct Kernel {
    int radius = 0;
    std::vector<double> w;  // (2r+1)^2, row-major
    double at(int x, int y) const {
        return w[size_t((y + radius) * (2 * radius + 1) + x + radius)];
    }
};

// Spatial contrast sensitivity filter (sum of two Gaussians, Sec. 4.1), normalised to sum 1.
Kernel csfKernel(double a1, double b1, double a2, double b2, double ppd) {
    Kernel k;
    k.radius = int(std::ceil(3.0 * std::sqrt(0.04 / (2.0 * std::numbers::pi * std::numbers::pi)) *
                             ppd));  // widest b: 0.04
    int n = 2 * k.radius + 1;
    k.w.resize(size_t(n) * n);
    double sum = 0.0;
    for (int y = -k.radius; y <= k.radius; ++y)
        for (int x = -k.radius; x <= k.radius; ++x) {
            double z = (x * x + y * y) / (ppd * ppd);
            double v = a1 * std::sqrt(std::numbers::pi / b1) *
                           std::exp(-std::numbers::pi * std::numbers::pi * z / b1) +
                       a2 * std::sqrt(std::numbers::pi / b2) *
                           std::exp(-std::numbers::pi * std::numbers::pi * z / b2);
            k.w[size_t((y + k.radius) * n + x + k.radius)] = v;
            sum += v;
        }
    for (double& v : k.w) v /= sum;
    return k;
}

// Edge (first derivative) or point (second derivative) detector along x (Sec. 5.1), positive
// weights normalised to sum 1 and negative ones to -1.
Kernel featureKernel(bool point, double ppd) {
    double sd = 0.5 * 0.082 * ppd;
    Kernel k;
    k.radius = int(std::ceil(3.0 * sd));
    int n = 2 * k.radius + 1;
    k.w.resize(size_t(n) * n);
    double pos = 0.0, neg = 0.0;
    for (int y = -k.radius; y <= k.radius; ++y)
        for (int x = -k.radius; x <= k.radius; ++x) {
            double g = std::exp(-(x * x + y * y) / (2.0 * sd * sd));
            double v = point ? (x * x / (sd * sd) - 1.0) * g : -x * g;
            k.w[size_t((y + k.radius) * n + x + k.radius)] = v;
            (v > 0 ? pos : neg) += v;
        }
    for (double& v : k.w) v = v > 0 ? v / pos : (v < 0 ? v / -neg : 0.0);
    return k;
}

// One channel, row-major; borders replicate the edge pixels.
std::vector<double> convolve(const std::vector<double>& img, int w, int h, const Kernel& k,
                             bool transpose) {
    std::vector<double> out(img.size(), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double s = 0.0;
            for (int j = -k.radius; j <= k.radius; ++j) {
                int yy = std::clamp(y + j, 0, h - 1);
                for (int i = -k.radius; i <= k.radius; ++i) {
                    int xx = std::clamp(x + i, 0, w - 1);
                    s += (transpose ? k.at(j, i) : k.at(i, j)) * img[size_t(yy) * w + xx];
                }
            }
            out[size_t(y) * w + x] = s;
        }
    return out;
}

Vec3 rgbOf(const ImageData& img, size_t p) {
    const float* v = &img.pixels[p * img.channels];
    return img.channels >= 3 ? Vec3{v[0], v[1], v[2]} : Vec3{v[0], v[0], v[0]};
}

void checkPair(const ImageData& a, const ImageData& b, const char* fn) {
    if (a.width != b.width || a.height != b.height)
        throw UserError(std::string(fn) + ": image is " + std::to_string(a.width) + "x" +
                        std::to_string(a.height) + " but the reference is " +
                        std::to_string(b.width) + "x" + std::to_string(b.height));
    if (a.width == 0 || a.height == 0) throw UserError(std::string(fn) + ": empty image");
}

// LDR-FLIP of images already in linear RGB clamped to [0,1] (sRGB decoded).
ImageData flipLinear(const std::vector<Vec3>& test, const std::vector<Vec3>& ref, int w, int h,
                     double ppd) {
    const Kernel csf[3] = {csfKernel(1.0, 0.0047, 0.0, 1e-5, ppd),
                           csfKernel(1.0, 0.0053, 0.0, 1e-5, ppd),
                           csfKernel(34.1, 0.04, 13.5, 0.025, ppd)};
    const Kernel edge = featureKernel(false, ppd), point = featureKernel(true, ppd);
    size_t n = size_t(w) * h;
    struct Prepared {
        std::vector<Vec3> lab;              // CSF-filtered, Hunt-adjusted L*a*b*
        std::vector<double> edges, points;  // feature magnitudes
    };
    auto prepare = [&](const std::vector<Vec3>& rgb) {
        std::vector<double> ch[3];
        for (auto& c : ch) c.resize(n);
        std::vector<double> yNorm(n);
        for (size_t p = 0; p < n; ++p) {
            Vec3 o = xyzToYcxcz(linearToXyz(rgb[p]));
            for (int c = 0; c < 3; ++c) ch[c][p] = o[c];
            yNorm[p] = (o[0] + 16.0) / 116.0;
        }
        for (int c = 0; c < 3; ++c) ch[c] = convolve(ch[c], w, h, csf[c], false);
        Prepared out;
        out.lab.resize(n);
        for (size_t p = 0; p < n; ++p) {
            Vec3 lin = xyzToLinear(ycxczToXyz({ch[0][p], ch[1][p], ch[2][p]}));
            for (double& v : lin) v = std::clamp(v, 0.0, 1.0);
            out.lab[p] = linearToHuntLab(lin);
        }
        auto ex = convolve(yNorm, w, h, edge, false), ey = convolve(yNorm, w, h, edge, true);
        auto px = convolve(yNorm, w, h, point, false), py = convolve(yNorm, w, h, point, true);
        out.edges.resize(n);
        out.points.resize(n);
        for (size_t p = 0; p < n; ++p) {
            out.edges[p] = std::hypot(ex[p], ey[p]);
            out.points[p] = std::hypot(px[p], py[p]);
        }
        return out;
    };
    Prepared t = prepare(test), r = prepare(ref);
    constexpr double qc = 0.7, qf = 0.5, pc = 0.4, pt = 0.95;
    const double cmax = std::pow(hyab(linearToHuntLab({0, 1, 0}), linearToHuntLab({0, 0, 1})), qc);
    ImageData out = ImageData::make(uint32_t(w), uint32_t(h), 1);
    for (size_t p = 0; p < n; ++p) {
        double e = std::pow(hyab(t.lab[p], r.lab[p]), qc);
        double ec = e < pc * cmax ? pt / (pc * cmax) * e
                                  : pt + (e - pc * cmax) / (cmax - pc * cmax) * (1.0 - pt);
        double ef =
            std::max(std::abs(r.edges[p] - t.edges[p]), std::abs(r.points[p] - t.points[p]));
        ef = std::pow(ef / std::sqrt(2.0), qf);
        out.pixels[p] = float(std::pow(ec, 1.0 - ef));
    }
    return out;
}

// ACES (Narkowicz fit) with the 0.6 pre-exposure folded in, as HDR-FLIP uses it.
constexpr double kAces[6] = {0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14};
double aces(double x) {
    double num = kAces[0] * x * x + kAces[1] * x + kAces[2];
    double den = kAces[3] * x * x + kAces[4] * x + kAces[5];
    return std::isinf(x) ? 1.0 : std::clamp(num / den, 0.0, 1.0);
}
// The x with aces(x) = t.
double acesInverse(double t) {
    double c0 = (kAces[1] - kAces[4] * t) / (kAces[0] - kAces[3] * t);
    double c1 = (kAces[2] - kAces[5] * t) / (kAces[0] - kAces[3] * t);
    return -0.5 * c0 + std::sqrt(0.25 * c0 * c0 - c1);
}

}  // namespace

ImageData flipLdr(const ImageData& test, const ImageData& reference, double ppd) {
    checkPair(test, reference, "flip");
    size_t n = size_t(test.width) * test.height;
    std::vector<Vec3> t(n), r(n);
    for (size_t p = 0; p < n; ++p) {
        Vec3 a = rgbOf(test, p), b = rgbOf(reference, p);
        for (int c = 0; c < 3; ++c) {
            t[p][c] = srgbToLinear(std::clamp(nonNegative(a[c]), 0.0, 1.0));
            r[p][c] = srgbToLinear(std::clamp(nonNegative(b[c]), 0.0, 1.0));
        }
    }
    return flipLinear(t, r, int(test.width), int(test.height), ppd);
}

ImageData flipHdr(const ImageData& test, const ImageData& reference, double ppd) {
    checkPair(test, reference, "flip");
    size_t n = size_t(test.width) * test.height;
    std::vector<double> lum(n);
    for (size_t p = 0; p < n; ++p) {
        Vec3 c = rgbOf(reference, p);
        lum[p] =
            0.2126 * nonNegative(c[0]) + 0.7152 * nonNegative(c[1]) + 0.0722 * nonNegative(c[2]);
        if (std::isinf(lum[p])) lum[p] = 0.0;
    }
    double yMax = *std::max_element(lum.begin(), lum.end());
    // The median as numpy's 50th percentile (mean of the middle two for even counts).
    std::vector<double> sorted = lum;
    std::sort(sorted.begin(), sorted.end());
    double yMedian = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    double start = 0.0, stop = 0.0;
    if (yMax > 0.0) {
        double x = acesInverse(0.85);
        start = std::log2(x / yMax);
        stop = yMedian > 0.0 ? std::log2(x / yMedian) : start;
    }
    int exposures = std::max(2, int(std::ceil(stop - start)));
    double step = (stop - start) / (exposures - 1);
    ImageData out = ImageData::make(test.width, test.height, 1);
    std::vector<Vec3> t(n), r(n);
    for (int i = 0; i < exposures; ++i) {
        double scale = std::exp2(start + i * step);
        for (size_t p = 0; p < n; ++p) {
            Vec3 a = rgbOf(test, p), b = rgbOf(reference, p);
            // Exposed and tone mapped: LDR-FLIP's input (its sRGB encoding and decoding cancel).
            for (int c = 0; c < 3; ++c) {
                t[p][c] = aces(scale * nonNegative(a[c]));
                r[p][c] = aces(scale * nonNegative(b[c]));
            }
        }
        ImageData e = flipLinear(t, r, int(test.width), int(test.height), ppd);
        for (size_t p = 0; p < n; ++p) out.pixels[p] = std::max(out.pixels[p], e.pixels[p]);
    }
    return out;
}

double meanOf(const ImageData& img) {
    double s = 0.0;
    for (float v : img.pixels) s += v;
    return img.pixels.empty() ? 0.0 : s / double(img.pixels.size());
}

}  // namespace loom
