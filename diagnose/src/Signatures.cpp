#include <diagnose/Signatures.h>

#include <diagnose/RigEffects.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "Format.h"

namespace diagnose {

namespace {

using detail::kNaN;

double mean(const std::vector<double>& v) {
    return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

}  // namespace

double interpolateClamped(const std::vector<double>& x, const std::vector<double>& y, double xq) {
    if (xq <= x.front()) return y.front();
    if (xq >= x.back()) return y.back();
    return interpolate(x, y, xq);
}

void addSecondDifferences(const std::vector<double>& y, std::vector<double>& dd) {
    for (size_t i = 1; i + 1 < y.size(); ++i)
        dd.push_back(std::fabs(y[i + 1] - 2.0 * y[i] + y[i - 1]));
}

double calcNoise(std::vector<double> dd) {
    if (dd.empty()) return 0.0;
    std::nth_element(dd.begin(), dd.begin() + dd.size() / 2, dd.end());
    // median |N(0, 1)| = 0.6745
    return dd[dd.size() / 2] / (0.6745 * std::sqrt(6.0));
}

std::pair<double, double> calcLag(const std::vector<double>& t, const std::vector<double>& m,
                                  const std::vector<double>& s, double maxLag) {
    if (t.size() < 8) return {kNaN, kNaN};
    std::vector<double> dts;
    for (size_t i = 1; i < t.size(); ++i) dts.push_back(t[i] - t[i - 1]);
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    const double dt = dts[dts.size() / 2];
    if (!(dt > 0.0)) return {kNaN, kNaN};
    const long n = static_cast<long>((t.back() - t.front()) / dt) + 1;
    std::vector<double> a(n), b(n);
    for (long i = 0; i < n; ++i) {
        const double ti = t.front() + i * dt;
        a[i] = interpolateClamped(t, m, ti);
        b[i] = interpolateClamped(t, s, ti);
    }
    const double ma = mean(a), mb = mean(b);
    for (double& v : a) v -= ma;
    for (double& v : b) v -= mb;
    const long K = std::min<long>(static_cast<long>(maxLag / dt), n / 4);
    std::vector<double> c(2 * K + 1, -2.0);
    for (long k = -K; k <= K; ++k) {
        double sab = 0.0, saa = 0.0, sbb = 0.0;
        for (long i = std::max(0L, k); i < std::min(n, n + k); ++i) {
            sab += a[i] * b[i - k];
            saa += a[i] * a[i];
            sbb += b[i - k] * b[i - k];
        }
        c[k + K] = saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : -2.0;
    }
    const long best = std::max_element(c.begin(), c.end()) - c.begin();
    double shift = double(best - K);
    if (best > 0 && best < 2 * K) {
        const double y0 = c[best - 1], y1 = c[best], y2 = c[best + 1];
        const double den = y0 - 2.0 * y1 + y2;
        if (den < 0.0) shift += 0.5 * (y0 - y2) / den;
    }
    return {shift * dt, c[best]};
}

Signature calcSeriesSignature(const std::string& channel, const std::vector<double>& t,
                              const std::vector<double>& m, const std::vector<double>& sim,
                              double maxLag) {
    Signature s;
    s.channel = channel;
    std::vector<double> res(m.size());
    for (size_t i = 0; i < res.size(); ++i) res[i] = m[i] - sim[i];
    s.bias = mean(res);
    const double ms = mean(sim), mm = mean(m), mt = mean(t);
    double sss = 0.0, ssm = 0.0, stt = 0.0, str = 0.0;
    for (size_t i = 0; i < res.size(); ++i) {
        sss += (sim[i] - ms) * (sim[i] - ms);
        ssm += (sim[i] - ms) * (m[i] - mm);
        stt += (t[i] - mt) * (t[i] - mt);
        str += (t[i] - mt) * (res[i] - s.bias);
    }
    s.scale = sss > 0.0 ? ssm / sss - 1.0 : kNaN;
    s.drift = stt > 0.0 ? str / stt : kNaN;
    const auto [lag, corr] = calcLag(t, m, sim, maxLag);
    s.lag = lag;
    s.lagCorrelation = corr;
    return s;
}

RegimeStats calcRegimeStats(const std::string& channel, const std::string& regime,
                            const std::vector<double>& v, double totalSquared) {
    RegimeStats st;
    st.channel = channel;
    st.regime = regime;
    st.samples = static_cast<int>(v.size());
    double ss = 0.0, sum = 0.0, mx = 0.0;
    for (double x : v) ss += x * x, sum += x, mx = std::max(mx, std::fabs(x));
    st.rmse = v.empty() ? 0.0 : std::sqrt(ss / double(v.size()));
    st.bias = v.empty() ? 0.0 : sum / double(v.size());
    st.maxError = mx;
    st.share = totalSquared > 0.0 ? ss / totalSquared : 0.0;
    return st;
}

GapMetrics calcPairedMetrics(const std::string& channel, const std::vector<double>& measured,
                             const std::vector<double>& simulated) {
    GapMetrics g;
    g.channel = channel;
    std::vector<double> d = measured, sim = simulated;
    g.samples = static_cast<int>(d.size());
    if (d.empty()) return g;
    double sum = 0.0, sum2 = 0.0;
    for (size_t i = 0; i < d.size(); ++i) {
        const double e = sim[i] - d[i];
        sum += e, sum2 += e * e;
        g.maxError = std::max(g.maxError, std::fabs(e));
    }
    g.rmse = std::sqrt(sum2 / double(d.size()));
    g.meanError = sum / double(d.size());
    // Equal sample counts: the area between the two empirical CDFs is the mean distance
    // between the sorted samples.
    std::sort(d.begin(), d.end());
    std::sort(sim.begin(), sim.end());
    double area = 0.0;
    for (size_t i = 0; i < d.size(); ++i) area += std::fabs(d[i] - sim[i]);
    g.areaMetric = area / double(d.size());
    return g;
}

}  // namespace diagnose
