// Exact predicates: expansion arithmetic and the filter's error analysis.
//
// Filter bound (orient3d). With u = b-a, v = c-a, w = d-a the filter evaluates
//     det = w.x*(u.y*v.z - u.z*v.y) + w.y*(...) + w.z*(...)
// Every one of the six exact terms (+-w_i u_j v_k, built from the exact differences) reaches the result through at
// most 8 roundings: 3 differences, the product u_j*v_k, the subtraction, the product by w_i and 2 additions. The
// standard model fl(x op y) = (x op y)(1 + d), |d| <= eps, gives |det~ - det| <= gamma_8 * T with
// gamma_8 = 8 eps / (1 - 8 eps) and T the sum of the absolute exact terms. The permanent P~ that the filter computes
// (same expression with absolute values) has the same 8 roundings per term, so T <= P~ / (1 - eps)^8, and
// gamma_8 / (1 - eps)^8 < 8 eps (1 + 17 eps). The filter multiplies P~ by 8 eps (1 + 64 eps) (rounded once more,
// still above 8 eps (1 + 62 eps) P~), which covers it with a relative margin of more than 40 eps. The 2D case has 4
// roundings per term (2 differences, product, subtraction) and uses 4 eps (1 + 64 eps).
// Underflow: sums and differences are exact in the subnormal range, but each product may lose up to 2^-1075
// absolutely. In orient3d the two products of a normal component n_k lose at most 2^-1074 together, which the
// multiplication by w_k scales by |w_k|, and the three final products add 3 * 2^-1075: in all at most
// U = 2^-1072 (|w.x| + |w.y| + |w.z| + 1) (in orient2d at most 2^-1074). The filter decides only when its bound
// exceeds 2^-1000 (|w.x| + |w.y| + |w.z| + 1) (in 2D: 2^-1000), so U < 2^-72 * bound, far inside the margin. That
// test is computed in the normal range (no subnormal operands, which are slow on common hardware). Overflow produces
// inf or NaN, for which the comparisons fail and the exact stage decides.
//
// Exact evaluation, floating-point expansions (every non-zero coordinate in [2^-300, 2^300]). Each difference
// b_i - a_i is computed exactly as a two-term expansion (Two-Diff), then the determinant is expanded with exact
// products (Two-Product via FMA or Dekker's splitting) and exact sums of non-overlapping expansions (merge by
// magnitude, then a Two-Sum sweep), with zero elimination. The sign of a non-overlapping expansion is the sign of its
// largest (last) component. In that range every component is a multiple of 2^-352 and below 2^302 in magnitude, so
// products of three are multiples of 2^-1056 (no bits lost to underflow) and far from overflow.
//
// Exact evaluation, big integers (any other finite input). Every double is an integer multiple of 2^-1074; after
// scaling by 2^-E (E the lowest exponent of the inputs' integer significands) all coordinates are integers below
// 2^2098, and the determinant is evaluated with fixed-size sign-magnitude integers (products of three differences
// stay below 2^6300). Slow (tens of microseconds) but only reached for extreme inputs. Nothing allocates.
#include "exact/ExactPredicates.h"

#include <algorithm>
#include <atomic>
#include <cstddef>

namespace cullide::exact {

namespace {

std::atomic<std::uint64_t> gFallbacks{0};

// ---- error-free transformations ----

/// x + y == a + b exactly, x = fl(a + b).
inline void twoSum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bVirtual = x - a;
    const double aVirtual = x - bVirtual;
    y = (a - aVirtual) + (b - bVirtual);
}

/// Same as twoSum, valid when |a| >= |b| (or a == 0).
inline void fastTwoSum(double a, double b, double& x, double& y) {
    x = a + b;
    y = b - (x - a);
}

/// x + y == a - b exactly, x = fl(a - b).
inline void twoDiff(double a, double b, double& x, double& y) {
    x = a - b;
    const double bVirtual = a - x;
    const double aVirtual = x + bVirtual;
    y = (a - aVirtual) + (bVirtual - b);
}

#if defined(__FMA__) || defined(__ARM_FEATURE_FMA) || defined(__FMA4__)
/// x + y == a * b exactly, x = fl(a * b).
inline void twoProduct(double a, double b, double& x, double& y) {
    x = a * b;
    y = std::fma(a, b, -x);
}
#else
/// Dekker/Veltkamp: a == hi + lo with hi, lo of at most 26 significant bits each.
inline void split(double a, double& hi, double& lo) {
    constexpr double kSplitter = 134217729.0;  // 2^27 + 1
    const double c = kSplitter * a;
    const double big = c - a;
    hi = c - big;
    lo = a - hi;
}

/// x + y == a * b exactly, x = fl(a * b).
inline void twoProduct(double a, double b, double& x, double& y) {
    x = a * b;
    double ahi, alo, bhi, blo;
    split(a, ahi, alo);
    split(b, bhi, blo);
    const double err1 = x - ahi * bhi;
    const double err2 = err1 - alo * bhi;
    const double err3 = err2 - ahi * blo;
    y = alo * blo - err3;
}
#endif

// ---- expansions: arrays of non-overlapping components in increasing magnitude, without zeros ----

/// Exact a - b as an expansion of 0..2 components; returns the length.
inline int diffExpansion(double a, double b, double* h) {
    double x, y;
    twoDiff(a, b, x, y);
    int n = 0;
    if (y != 0.0) h[n++] = y;
    if (x != 0.0) h[n++] = x;
    return n;
}

/// h = e * s. h needs room for 2 * en components; returns the length.
int scaleExpansion(int en, const double* e, double s, double* h) {
    if (en == 0 || s == 0.0) return 0;
    int hn = 0;
    double q, t;
    twoProduct(e[0], s, q, t);
    if (t != 0.0) h[hn++] = t;
    for (int i = 1; i < en; ++i) {
        double p1, p0;
        twoProduct(e[i], s, p1, p0);
        double sum;
        twoSum(q, p0, sum, t);
        if (t != 0.0) h[hn++] = t;
        fastTwoSum(p1, sum, q, t);
        if (t != 0.0) h[hn++] = t;
    }
    if (q != 0.0) h[hn++] = q;
    return hn;
}

/// h = e + f. h needs room for en + fn components and must not alias e or f; returns the length.
int sumExpansions(int en, const double* e, int fn, const double* f, double* h) {
    if (en == 0) {
        for (int i = 0; i < fn; ++i) h[i] = f[i];
        return fn;
    }
    if (fn == 0) {
        for (int i = 0; i < en; ++i) h[i] = e[i];
        return en;
    }
    int i = 0, j = 0;
    // Next component in order of increasing magnitude (a merge of the two sorted sequences).
    auto next = [&]() -> double {
        if (j >= fn || (i < en && std::fabs(e[i]) < std::fabs(f[j]))) return e[i++];
        return f[j++];
    };
    int hn = 0;
    double q = next();
    double t;
    fastTwoSum(next(), q, q, t);
    if (t != 0.0) h[hn++] = t;
    while (i < en || j < fn) {
        const double g = next();
        twoSum(q, g, q, t);
        if (t != 0.0) h[hn++] = t;
    }
    if (q != 0.0) h[hn++] = q;
    return hn;
}

/// h = e * f. h needs room for 2 * en * fn components; scratch needs room for 2 * (2 * en * fn) components.
int productExpansions(int en, const double* e, int fn, const double* f, double* h, double* scratch) {
    int hn = 0;
    double* term = scratch;
    double* acc = scratch + 2 * en * fn;
    for (int k = 0; k < fn; ++k) {
        const int tn = scaleExpansion(en, e, f[k], term);
        const int an = sumExpansions(hn, h, tn, term, acc);
        for (int m = 0; m < an; ++m) h[m] = acc[m];
        hn = an;
    }
    return hn;
}

inline void negate(int n, double* e) {
    for (int i = 0; i < n; ++i) e[i] = -e[i];
}

inline int signOf(int n, const double* e) {
    if (n == 0) return 0;
    return e[n - 1] > 0.0 ? 1 : -1;
}

/// Exact a*d - b*c for expansions of at most 2 components each. h needs 16 components.
int det2(int an, const double* a, int bn, const double* b, int cn, const double* c, int dn, const double* d,
         double* h) {
    double ad[8], bc[8], scratch[16];
    const int adn = productExpansions(an, a, dn, d, ad, scratch);
    const int bcn = productExpansions(bn, b, cn, c, bc, scratch);
    negate(bcn, bc);
    return sumExpansions(adn, ad, bcn, bc, h);
}

// ---- big integers for inputs outside the expansion range ----

/// Sign-magnitude integer with little-endian 32-bit limbs and a fixed capacity.
struct BigInt {
    static constexpr int kCapacity = 208;  // >= 6300 bits
    std::uint32_t limb[kCapacity];
    int size = 0;  ///< used limbs; limb[size - 1] != 0 unless size == 0
    int sign = 0;  ///< -1, 0 or +1

    void trim() {
        while (size > 0 && limb[size - 1] == 0) --size;
        if (size == 0) sign = 0;
    }
};

/// r = sign * m * 2^shift.
void setShifted(BigInt& r, std::uint64_t m, int shift, int sign) {
    const int words = shift / 32, bits = shift % 32;
    for (int i = 0; i < words + 4; ++i) r.limb[i] = 0;
    // m * 2^bits spans at most 53 + 31 bits, i.e. three limbs.
    const std::uint64_t lo = m << bits;
    const std::uint64_t hi = bits == 0 ? 0 : (m >> (64 - bits));
    r.limb[words] = static_cast<std::uint32_t>(lo);
    r.limb[words + 1] = static_cast<std::uint32_t>(lo >> 32);
    r.limb[words + 2] = static_cast<std::uint32_t>(hi);
    r.limb[words + 3] = 0;
    r.size = words + 4;
    r.sign = sign;
    r.trim();
}

int compareMagnitude(const BigInt& a, const BigInt& b) {
    if (a.size != b.size) return a.size < b.size ? -1 : 1;
    for (int i = a.size - 1; i >= 0; --i) {
        if (a.limb[i] != b.limb[i]) return a.limb[i] < b.limb[i] ? -1 : 1;
    }
    return 0;
}

/// r = a + (bSign) * |b| with r's sign handled; r may not alias a or b.
void addSigned(const BigInt& a, const BigInt& b, int bSign, BigInt& r) {
    if (bSign == 0 || b.size == 0) {
        r = a;
        return;
    }
    if (a.sign == 0) {
        r = b;
        r.sign = bSign;
        return;
    }
    if (a.sign == bSign) {
        const int n = std::max(a.size, b.size);
        std::uint64_t carry = 0;
        for (int i = 0; i < n; ++i) {
            const std::uint64_t s = carry + (i < a.size ? a.limb[i] : 0u) + (i < b.size ? b.limb[i] : 0u);
            r.limb[i] = static_cast<std::uint32_t>(s);
            carry = s >> 32;
        }
        r.limb[n] = static_cast<std::uint32_t>(carry);
        r.size = n + 1;
        r.sign = a.sign;
        r.trim();
        return;
    }
    // Opposite signs: subtract the smaller magnitude from the larger.
    const int c = compareMagnitude(a, b);
    if (c == 0) {
        r.size = 0;
        r.sign = 0;
        return;
    }
    const BigInt& big = c > 0 ? a : b;
    const BigInt& small = c > 0 ? b : a;
    std::int64_t borrow = 0;
    for (int i = 0; i < big.size; ++i) {
        std::int64_t d = static_cast<std::int64_t>(big.limb[i]) - (i < small.size ? small.limb[i] : 0u) - borrow;
        borrow = d < 0 ? 1 : 0;
        if (d < 0) d += std::int64_t{1} << 32;
        r.limb[i] = static_cast<std::uint32_t>(d);
    }
    r.size = big.size;
    r.sign = c > 0 ? a.sign : bSign;
    r.trim();
}

/// r = a * b; r may not alias a or b.
void multiply(const BigInt& a, const BigInt& b, BigInt& r) {
    if (a.sign == 0 || b.sign == 0) {
        r.size = 0;
        r.sign = 0;
        return;
    }
    const int n = a.size + b.size;
    for (int i = 0; i < n; ++i) r.limb[i] = 0;
    for (int i = 0; i < a.size; ++i) {
        std::uint64_t carry = 0;
        const std::uint64_t ai = a.limb[i];
        for (int j = 0; j < b.size; ++j) {
            const std::uint64_t t = ai * b.limb[j] + r.limb[i + j] + carry;
            r.limb[i + j] = static_cast<std::uint32_t>(t);
            carry = t >> 32;
        }
        r.limb[i + b.size] = static_cast<std::uint32_t>(carry);
    }
    r.size = n;
    r.sign = a.sign * b.sign;
    r.trim();
}

/// Integer significand and exponent of a finite non-zero double: x == m * 2^e, m < 2^53.
void decompose(double x, std::uint64_t& m, int& e) {
    if (!std::isfinite(x)) {  // outside the contract; keep the conversion well-defined
        m = 0;
        e = 0;
        return;
    }
    int k = 0;
    const double f = std::frexp(std::fabs(x), &k);  // f in [0.5, 1)
    m = static_cast<std::uint64_t>(std::ldexp(f, 53));
    e = k - 53;
}

/// Converts n doubles to integers scaled by a common power of two (the sign of any polynomial that is homogeneous in
/// the coordinates is unchanged).
void toScaledIntegers(const double* x, int n, BigInt* out) {
    std::uint64_t m[12];
    int e[12];
    int lowest = 0;
    bool any = false;
    for (int i = 0; i < n; ++i) {
        if (x[i] == 0.0) continue;
        decompose(x[i], m[i], e[i]);
        lowest = any ? std::min(lowest, e[i]) : e[i];
        any = true;
    }
    for (int i = 0; i < n; ++i) {
        if (x[i] == 0.0) {
            out[i].size = 0;
            out[i].sign = 0;
        } else {
            setShifted(out[i], m[i], e[i] - lowest, x[i] < 0.0 ? -1 : 1);
        }
    }
}

/// u_i v_j - u_j v_i.
void cross2(const BigInt& ui, const BigInt& uj, const BigInt& vi, const BigInt& vj, BigInt& r) {
    BigInt p, q;
    multiply(ui, vj, p);
    multiply(uj, vi, q);
    addSigned(p, q, -q.sign, r);
}

int orient3dBig(const double* a, const double* b, const double* c, const double* d) {
    const double x[12] = {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]};
    BigInt v[12];
    toScaledIntegers(x, 12, v);
    BigInt u[3], w[3], z[3];
    for (int k = 0; k < 3; ++k) {
        addSigned(v[3 + k], v[k], -v[k].sign, u[k]);
        addSigned(v[6 + k], v[k], -v[k].sign, w[k]);
        addSigned(v[9 + k], v[k], -v[k].sign, z[k]);
    }
    BigInt det, term, n, acc;
    det.size = 0;
    det.sign = 0;
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        cross2(u[i], u[j], w[i], w[j], n);
        multiply(z[k], n, term);
        addSigned(det, term, term.sign, acc);
        det = acc;
    }
    return det.sign;
}

int orient2dBig(double ax, double ay, double bx, double by, double cx, double cy) {
    const double x[6] = {ax, ay, bx, by, cx, cy};
    BigInt v[6];
    toScaledIntegers(x, 6, v);
    BigInt ux, uy, wx, wy, det;
    addSigned(v[2], v[0], -v[0].sign, ux);
    addSigned(v[3], v[1], -v[1].sign, uy);
    addSigned(v[4], v[0], -v[0].sign, wx);
    addSigned(v[5], v[1], -v[1].sign, wy);
    cross2(ux, uy, wx, wy, det);
    return det.sign;
}

/// Every coordinate is 0 or of magnitude in [2^-300, 2^300]: the expansion arithmetic is exact.
inline bool inExpansionRange(const double* x, int n) {
    for (int i = 0; i < n; ++i) {
        const double m = std::fabs(x[i]);
        if (m != 0.0 && !(m >= 0x1p-300 && m <= 0x1p+300)) return false;
    }
    return true;
}

int orient3dExpansion(const double* a, const double* b, const double* c, const double* d);
int orient2dExpansion(double ax, double ay, double bx, double by, double cx, double cy);

inline bool samePoint3(const double* p, const double* q) { return p[0] == q[0] && p[1] == q[1] && p[2] == q[2]; }

}  // namespace

int orient3dExact(const double* a, const double* b, const double* c, const double* d) {
    // Repeated points (shared vertices, degenerate triangles) make the determinant exactly zero: answer at once.
    if (samePoint3(a, b) || samePoint3(a, c) || samePoint3(a, d) || samePoint3(b, c) || samePoint3(b, d) ||
        samePoint3(c, d)) {
        return 0;
    }
    if (inExpansionRange(a, 3) && inExpansionRange(b, 3) && inExpansionRange(c, 3) && inExpansionRange(d, 3)) {
        return orient3dExpansion(a, b, c, d);
    }
    return orient3dBig(a, b, c, d);
}

int orient2dExact(double ax, double ay, double bx, double by, double cx, double cy) {
    if ((ax == bx && ay == by) || (ax == cx && ay == cy) || (bx == cx && by == cy)) return 0;
    const double x[6] = {ax, ay, bx, by, cx, cy};
    if (inExpansionRange(x, 6)) return orient2dExpansion(ax, ay, bx, by, cx, cy);
    return orient2dBig(ax, ay, bx, by, cx, cy);
}

int orient3dExactBigInt(const double* a, const double* b, const double* c, const double* d) {
    return orient3dBig(a, b, c, d);
}

int orient2dExactBigInt(double ax, double ay, double bx, double by, double cx, double cy) {
    return orient2dBig(ax, ay, bx, by, cx, cy);
}

namespace {

int orient3dExpansion(const double* a, const double* b, const double* c, const double* d) {
    double u[3][2], v[3][2], w[3][2];
    int un[3], vn[3], wn[3];
    for (int k = 0; k < 3; ++k) {
        un[k] = diffExpansion(b[k], a[k], u[k]);
        vn[k] = diffExpansion(c[k], a[k], v[k]);
        wn[k] = diffExpansion(d[k], a[k], w[k]);
    }
    // det = sum_k w_k * n_k with n_k = u_i v_j - u_j v_i, (i, j) = (k+1, k+2) mod 3.
    double terms[3][64];
    int tn[3];
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        double n[16];
        const int nn = det2(un[i], u[i], un[j], u[j], vn[i], v[i], vn[j], v[j], n);
        double scratch[128];
        tn[k] = productExpansions(nn, n, wn[k], w[k], terms[k], scratch);
    }
    double s01[128];
    const int s01n = sumExpansions(tn[0], terms[0], tn[1], terms[1], s01);
    double total[192];
    const int totaln = sumExpansions(s01n, s01, tn[2], terms[2], total);
    return signOf(totaln, total);
}

int orient2dExpansion(double ax, double ay, double bx, double by, double cx, double cy) {
    double ux[2], uy[2], vx[2], vy[2];
    const int uxn = diffExpansion(bx, ax, ux);
    const int uyn = diffExpansion(by, ay, uy);
    const int vxn = diffExpansion(cx, ax, vx);
    const int vyn = diffExpansion(cy, ay, vy);
    double h[16];
    const int hn = det2(uxn, ux, uyn, uy, vxn, vx, vyn, vy, h);
    return signOf(hn, h);
}

}  // namespace

namespace detail {

int orient3dFallback(const double* a, const double* b, const double* c, const double* d) {
    gFallbacks.fetch_add(1, std::memory_order_relaxed);
    return orient3dExact(a, b, c, d);
}

int orient2dFallback(double ax, double ay, double bx, double by, double cx, double cy) {
    gFallbacks.fetch_add(1, std::memory_order_relaxed);
    return orient2dExact(ax, ay, bx, by, cx, cy);
}

}  // namespace detail

std::uint64_t exactFallbackCount() noexcept { return gFallbacks.load(std::memory_order_relaxed); }

void resetExactFallbackCount() noexcept { gFallbacks.store(0, std::memory_order_relaxed); }

}  // namespace cullide::exact
