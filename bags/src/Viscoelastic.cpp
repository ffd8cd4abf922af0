#include <bags/Viscoelastic.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bags {

double calcPronyPhi(double x) {
    if (std::isinf(x)) return 0.0;
    if (std::abs(x) < 1e-8) return 1.0 - 0.5 * x;
    return -std::expm1(-x) / x;
}

bool PronySeries::isOn() const {
    for (const PronyTerm& t : terms)
        if (t.g > 0.0) return true;
    return false;
}

double PronySeries::getLongTermFraction() const {
    double s = 0.0;
    for (const PronyTerm& t : terms) s += t.g;
    return 1.0 - s;
}

void PronySeries::validate() const {
    auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
    if (static_cast<int>(terms.size()) > kMaxTerms)
        fail("Prony series: " + std::to_string(terms.size()) + " terms; use at most " +
             std::to_string(kMaxTerms));
    double sum = 0.0;
    for (size_t i = 0; i < terms.size(); ++i) {
        const PronyTerm& t = terms[i];
        std::ostringstream s;
        s << "Prony term " << i + 1 << ": ";
        if (!(t.g >= 0.0 && t.g < 1.0)) {
            s << "g = " << t.g << " is invalid; use a relative modulus 0 <= g < 1 (e.g. 0.1)";
            fail(s.str());
        }
        if (!(t.tau >= kMinTau && t.tau <= kMaxTau)) {
            s << "tau = " << t.tau << " s is invalid; use a relaxation time of " << kMinTau
              << " s to " << kMaxTau << " s (e.g. 20 s)";
            fail(s.str());
        }
        sum += t.g;
    }
    if (!(sum <= kMaxSum)) {
        std::ostringstream s;
        s << "Prony series: the relative moduli sum to " << sum << "; use a sum of at most "
          << kMaxSum << " (the long-term modulus g_inf = 1 - sum g must stay positive)";
        fail(s.str());
    }
}

double PronySeries::calcStepScale(double dt) const {
    const double ginf = getLongTermFraction();
    double a = 1.0;
    for (const PronyTerm& t : terms)
        if (t.g > 0.0) a += t.g / ginf * calcPronyPhi(dt / t.tau);
    return a;
}

double PronySeries::calcRelaxation(double t) const {
    double G = getLongTermFraction();
    for (const PronyTerm& p : terms) G += p.g * std::exp(-t / p.tau);
    return G;
}

std::string PronySeries::describe() const {
    std::ostringstream s;
    for (size_t i = 0; i < terms.size(); ++i)
        s << (i ? "; " : "") << "g " << terms[i].g << ", tau " << terms[i].tau << " s";
    return s.str();
}

}  // namespace bags
