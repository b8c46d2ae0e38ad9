// exp(x) for x <= 0 written so that the compiler can vectorise loops over it (std::exp is a
// scalar library call). Within 2 ulp of std::exp; inputs below -700 give exp(-700) ~ 1e-304,
// which is zero for every use here (weights already scaled so that the largest is 1).
#pragma once
#include <cstdint>

#include "pointscale/detail/portable.h"

namespace pointscale {

inline double exp_nonpositive(double x) {
  // x = k ln2 + r with |r| <= ln2 / 2: adding 1.5 * 2^52 rounds x / ln2 to an integer held in the
  // low mantissa bits (Cody-Waite reduction with ln2 split in two for precision).
  x = x > -700.0 ? x : -700.0;  // a select, not a branch, with -fno-trapping-math
  constexpr double shifter = 6755399441055744.0;
  const double kd = x * 1.4426950408889634 + shifter;
  const double k = kd - shifter;
  const double r = (x - k * 0.693145751953125) - k * 1.42860682030941723212e-6;
  // exp(r) by the Pade form of Cephes' exp: 1 + 2 p / (q - p).
  const double rr = r * r;
  const double p = r * ((1.26177193074810590878e-4 * rr + 3.02994407707441961300e-2) * rr + 9.99999999999999999910e-1);
  const double q = ((3.00198505138664455042e-6 * rr + 2.52448340349684104192e-3) * rr + 2.27265548208155028766e-1) * rr +
                   2.00000000000000000009e0;
  const double e = 1.0 + 2.0 * p / (q - p);
  // Multiply by 2^k by adding k to the exponent field; k >= -1010 keeps the result normal.
  const std::int64_t kbits = bit_cast<std::int64_t>(kd);
  const std::int64_t ebits = bit_cast<std::int64_t>(e);
  constexpr std::int64_t shifter_bits = 0x4338000000000000LL;
  return bit_cast<double>(ebits + ((kbits - shifter_bits) << 52));
}

}  // namespace pointscale
