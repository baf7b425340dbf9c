// the elementary functions that enter results, computed the same bits on every CPU and operating system.
//
// Why not the C library's: glibc picks its sin, cos, exp, log and pow at run time by the CPU (on x86-64 one version
// for CPUs with FMA, another without), and other libraries and architectures compute them differently again; each is
// within an ulp or so, but not the same ulp, so a run on an older CPU or another system would differ in the last bits
// and then everywhere (measured: 118 of the tiny preset's 271 datasets with glibc's non-FMA versions). These are
// built from IEEE additions, multiplications, divisions, square roots and exact scalings only (every file is
// compiled with -ffp-contract=off: no fused multiply-add the code does not ask for), so their results are fixed by
// the IEEE standard. The algorithms and coefficients are FreeBSD's msun (Sun's fdlibm): exp, log, sin and cos within
// 1 ulp of the exact value (tests/common/dmath_test.cpp checks them against the C library and a table of bits).
#pragma once

namespace divcoll::dmath {

double exp(double x);
double log(double x);
// sin and cos reduce their argument by π/2 in three parts (Cody and Waite): within 1 ulp for |x| < 2^20 (10⁶ rad);
// larger arguments (none in divcoll: its phases stay below 10⁴ rad) lose accuracy but keep their bits
double sin(double x);
double cos(double x);
// x^y as exp(y·log(x)): its relative error grows with |y·log(x)| (about 1e-14 at |y·log x| = 50: Adam's bias
// corrections, learning-rate schedules); x < 0 only for an integer y (else NaN), like std::pow
double pow(double x, double y);
// √(x² + y²) without the C library's hypot (whose algorithm differs between systems); for the magnitudes of lengths
// and gradients (no overflow below 1e150)
double hypot(double x, double y);

}  // namespace divcoll::dmath
