#pragma once
// Chi-square goodness-of-fit machinery shared by the sampling tests (pbrt-v3 chi2test: cells
// sorted by expectation, those expecting fewer than 5 samples pooled).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

namespace loom::test {

// Regularised upper incomplete gamma Q(a, x) (series / Lentz continued fraction, Numerical
// Recipes 3rd ed. Sec. 6.2).
inline double gammaQ(double a, double x) {
    if (x <= 0.0) return 1.0;
    const double lg = std::lgamma(a);
    if (x < a + 1.0) {
        double sum = 1.0 / a, term = sum;
        for (int n = 1; n < 100000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::abs(term) < std::abs(sum) * 1e-15) break;
        }
        return 1.0 - sum * std::exp(-x + a * std::log(x) - lg);
    }
    double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (std::abs(c) < 1e-300) c = 1e-300;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - lg) * h;
}

// Per-test significance after a Sidak correction over `tests` tests at overall level 0.01.
inline double sidak(int tests) {
    return 1.0 - std::pow(1.0 - 0.01, 1.0 / tests);
}

struct Chi2Result {
    double statistic = 0.0;
    int dof = 0;
    double pValue = 0.0;
    double stray = 0.0;     // samples in cells of expected frequency 0 (total)
    double maxStray = 0.0;  // ... in the worst such cell
};

inline Chi2Result chi2(const std::vector<double>& observed, const std::vector<double>& expected) {
    std::vector<size_t> order(observed.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    constexpr double kMinExpected = 5.0;
    Chi2Result r;
    double pooledObs = 0.0, pooledExp = 0.0;
    for (size_t i : order) {
        if (expected[i] <= 0.0) {
            r.stray += observed[i];
            r.maxStray = std::max(r.maxStray, observed[i]);
        } else if (expected[i] < kMinExpected || (pooledExp > 0.0 && pooledExp < kMinExpected)) {
            pooledObs += observed[i];
            pooledExp += expected[i];
        } else {
            const double d = observed[i] - expected[i];
            r.statistic += d * d / expected[i];
            ++r.dof;
        }
    }
    if (pooledExp > 0.0) {
        const double d = pooledObs - pooledExp;
        r.statistic += d * d / pooledExp;
        ++r.dof;
    }
    r.dof -= 1;
    r.pValue = r.dof > 0 ? gammaQ(0.5 * r.dof, 0.5 * r.statistic) : 1.0;
    return r;
}

}  // namespace loom::test
