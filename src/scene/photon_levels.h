// The block design of unbiased photon mapping in closed form (docs/PHOTON-MAPPING.md), for the
// loader's checks and the plan. Level k of a block multiplies the kernel area by s^k and the
// photon passes by m^k and is drawn with p(k) ~ r (1-r)^k, i.e. it continues with q = 1 - r.
// For a smooth photon density:
//   expected passes per sample        (1 - q) / (1 - q m)                  finite iff q m < 1
//   tail index of the sample error    a = ln(1/q) / (ln(1/q) - ln(m s) / 2)  finite mean iff a > 1
//   typical error against cost        cost^(-ln(m s) / (2 ln(1/q)))
//   finite variance would need q m s > 1: impossible with q m < 1 (the paper's theorem).
// The level cap K (levels 0 .. K-1) leaves the bias of a kernel at r_K, s^K times the base bias.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace telescope {

struct PhotonBlockTheory {
    double q = 0.0;               // continuation probability 1 - r
    double expectedPasses = 0.0;  // per sample, untruncated (infinite when q m >= 1)
    double tailIndex = 0.0;       // a (infinite when the correction's tail is light)
    double errorExponent = 0.0;   // typical error ~ cost^-exponent
};

inline PhotonBlockTheory photonBlockTheory(double r, double areaRatio, double growth) {
    PhotonBlockTheory t;
    t.q = 1.0 - r;
    const double qm = t.q * growth;
    t.expectedPasses = qm < 1.0 ? (1.0 - t.q) / (1.0 - qm) : std::numeric_limits<double>::infinity();
    const double lnInvQ = -std::log(t.q), half = 0.5 * std::log(growth * areaRatio);
    t.tailIndex = lnInvQ - half > 0.0 ? lnInvQ / (lnInvQ - half) : std::numeric_limits<double>::infinity();
    t.errorExponent = half / lnInvQ;
    return t;
}

// Expected passes per sample with the pmf truncated to levels 0 .. cap-1.
inline double photonExpectedPasses(double r, double growth, uint32_t cap) {
    const double q = 1.0 - r, norm = 1.0 - std::pow(q, cap);
    double sum = 0.0;
    for (uint32_t k = 0; k < cap; ++k) sum += r * std::pow(q, k) / norm * std::pow(growth, k);
    return sum;
}

// The default level cap: the truncation bias s^K below 1e-3 of the base bias.
constexpr double kPhotonTruncationBias = 1e-3;
inline uint32_t photonDefaultLevelCap(double areaRatio) {
    return uint32_t(std::ceil(std::log(kPhotonTruncationBias) / std::log(areaRatio)));
}

}  // namespace telescope
