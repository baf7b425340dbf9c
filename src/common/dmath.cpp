// FreeBSD msun's algorithms (e_exp.c, e_log.c, k_sin.c, k_cos.c and the medium case of e_rem_pio2.c), written
// again in C++ with the same coefficients and the same order of operations.
#include "common/dmath.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace divcoll::dmath {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ln 2 in two parts: the high part has 32 trailing zero bits, so k·ln2_hi is exact for |k| < 2^20
constexpr double kLn2Hi = 6.93147180369123816490e-01;
constexpr double kLn2Lo = 1.90821492927058770002e-10;

// sin and cos of x + y on |x + y| ≤ π/4 (y the tail of a reduced argument); k_sin.c and k_cos.c
double kernel_sin(double x, double y, bool has_tail) {
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  const double z = x * x, w = z * z;
  const double r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
  const double v = z * x;
  if (!has_tail) return x + v * (S1 + z * r);
  return x - ((z * (0.5 * y - v * r) - y) - v * S1);
}
double kernel_cos(double x, double y) {
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double z = x * x, w = z * z;
  const double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
  const double hz = 0.5 * z;
  const double u = 1.0 - hz;
  return u + (((1.0 - u) - hz) + (z * r - x * y));
}

// x = n·π/2 + (y0 + y1), |y0 + y1| ≤ π/4 (about), by π/2 in three parts; returns n mod 4
int reduce_pio2(double x, double& y0, double& y1) {
  constexpr double kInvPio2 = 6.36619772367581382433e-01;
  constexpr double kPio2_1 = 1.57079632673412561417e+00, kPio2_1t = 6.07710050650619224932e-11;
  constexpr double kPio2_2 = 6.07710050630396597660e-11, kPio2_2t = 2.02226624879595063154e-21;
  constexpr double kPio2_3 = 2.02226624871116645580e-21, kPio2_3t = 8.47842766036889956997e-32;
  const double fn = std::nearbyint(x * kInvPio2);
  double r = x - fn * kPio2_1;
  double w = fn * kPio2_1t;
  y0 = r - w;
  // two more parts of π/2 where the first left too few good bits (x near a multiple of π/2)
  uint64_t bx, by;
  std::memcpy(&bx, &x, 8);
  std::memcpy(&by, &y0, 8);
  const int ex = static_cast<int>((bx >> 52) & 0x7ff);
  if (ex - static_cast<int>((by >> 52) & 0x7ff) > 16) {
    double t = r;
    w = fn * kPio2_2;
    r = t - w;
    w = fn * kPio2_2t - ((t - r) - w);
    y0 = r - w;
    std::memcpy(&by, &y0, 8);
    if (ex - static_cast<int>((by >> 52) & 0x7ff) > 49) {
      t = r;
      w = fn * kPio2_3;
      r = t - w;
      w = fn * kPio2_3t - ((t - r) - w);
      y0 = r - w;
    }
  }
  y1 = (r - y0) - w;
  const double n4 = fn - 4.0 * std::floor(fn * 0.25);  // fn mod 4, exact
  return static_cast<int>(n4);
}
}  // namespace

double exp(double x) {
  // e_exp.c: x = k ln2 + r, |r| ≤ ln2/2; e^r by a rational form of a degree-5 polynomial in r²; then 2^k
  constexpr double P1 = 1.66666666666666019037e-01, P2 = -2.77777777770155933842e-03,
                   P3 = 6.61375632143793436117e-05, P4 = -1.65339022054652515390e-06,
                   P5 = 4.13813679705723846039e-08;
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  if (x != x) return x;
  if (x > 7.09782712893383973096e+02) return kInf;
  if (x < -7.45133219101941108420e+02) return 0.0;
  double hi = 0, lo = 0;
  int k = 0;
  const double ax = std::fabs(x);
  if (ax > 0.5 * kLn2Hi) {
    if (ax < 1.5 * kLn2Hi) {
      k = x > 0 ? 1 : -1;
    } else {
      k = static_cast<int>(kInvLn2 * x + (x > 0 ? 0.5 : -0.5));  // round half away from zero, by truncation
    }
    hi = x - k * kLn2Hi;
    lo = k * kLn2Lo;
    x = hi - lo;
  } else if (ax < 0x1p-28) {
    return 1.0 + x;
  }
  const double t = x * x;
  const double c = x - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
  if (k == 0) return 1.0 - ((x * c) / (c - 2.0) - x);
  const double y = 1.0 - ((lo - (x * c) / (2.0 - c)) - hi);
  return std::ldexp(y, k);  // an exact scaling (one rounding if the result is subnormal)
}

double log(double x) {
  // e_log.c: x = 2^k (1 + f), √2/2 ≤ 1 + f < √2; log(1 + f) = f − f²/2 + s (f²/2 + R(s²)), s = f / (2 + f)
  constexpr double Lg1 = 6.666666666666735130e-01, Lg2 = 3.999999999940941908e-01,
                   Lg3 = 2.857142874366239149e-01, Lg4 = 2.222219843214978396e-01,
                   Lg5 = 1.818357216161805012e-01, Lg6 = 1.531383769920937332e-01,
                   Lg7 = 1.479819860511658591e-01;
  if (x != x) return x;
  if (x < 0) return kNaN;
  if (x == 0) return -kInf;
  if (x == kInf) return x;
  int e = 0;
  double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1): exact
  if (m < 0.70710678118654752440) {
    m *= 2.0;
    --e;
  }
  const double f = m - 1.0;  // exact (Sterbenz)
  const double dk = e;
  if (f == 0) return dk * kLn2Hi + dk * kLn2Lo;
  const double s = f / (2.0 + f);
  const double z = s * s, w = z * z;
  const double t1 = w * (Lg2 + w * (Lg4 + w * Lg6));
  const double t2 = z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7)));
  const double R = t2 + t1;
  const double hfsq = 0.5 * f * f;
  return dk * kLn2Hi - ((hfsq - (s * (hfsq + R) + dk * kLn2Lo)) - f);
}

double sin(double x) {
  if (x != x || std::isinf(x)) return kNaN;
  if (std::fabs(x) <= 7.85398163397448278999e-01) return std::fabs(x) < 0x1p-27 ? x : kernel_sin(x, 0.0, false);
  double y0, y1;
  switch (reduce_pio2(x, y0, y1)) {
    case 0: return kernel_sin(y0, y1, true);
    case 1: return kernel_cos(y0, y1);
    case 2: return -kernel_sin(y0, y1, true);
    default: return -kernel_cos(y0, y1);
  }
}

double cos(double x) {
  if (x != x || std::isinf(x)) return kNaN;
  if (std::fabs(x) <= 7.85398163397448278999e-01) return std::fabs(x) < 0x1p-27 ? 1.0 : kernel_cos(x, 0.0);
  double y0, y1;
  switch (reduce_pio2(x, y0, y1)) {
    case 0: return kernel_cos(y0, y1);
    case 1: return -kernel_sin(y0, y1, true);
    case 2: return -kernel_cos(y0, y1);
    default: return kernel_sin(y0, y1, true);
  }
}

double pow(double x, double y) {
  if (y == 0 || x == 1) return 1.0;
  if (x != x || y != y) return kNaN;
  if (x == 0) return y > 0 ? 0.0 : kInf;
  if (x < 0) {
    if (std::nearbyint(y) != y) return kNaN;
    const double p = exp(y * log(-x));
    return std::fmod(y, 2.0) == 0 ? p : -p;
  }
  return exp(y * log(x));
}

double hypot(double x, double y) { return std::sqrt(x * x + y * y); }

}  // namespace divcoll::dmath
