#pragma once
// Four doubles as one GCC/Clang vector (AVX2 with -march=native; the compiler splits or
// scalarises it on narrower targets), for kernels that run four independent evaluations
// side by side — four segments of a term, or four point pairs of the contact kernel. Each
// lane computes exactly what the scalar code computes; only sums across lanes (done in a
// fixed order by lane_sum) differ in order from a scalar loop.
#include <cstring>
#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace knit::lanes {

constexpr int LANES = 4;
typedef double VecD __attribute__((vector_size(LANES * sizeof(double))));
typedef long long VecL __attribute__((vector_size(LANES * sizeof(long long))));

inline VecD splat(double x) {
  return VecD{} + x;
}
/// Loads/stores LANES doubles from/to any address.
inline VecD load(const double* p) {
  VecD v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(double* p, VecD v) {
  std::memcpy(p, &v, sizeof v);
}
/// Fixed-order reductions over the lanes.
inline double lane_sum(VecD v) {
  double s = v[0];
  for (int l = 1; l < LANES; ++l) s += v[l];
  return s;
}
inline double lane_min(VecD v) {
  double m = v[0];
  for (int l = 1; l < LANES; ++l) m = v[l] < m ? v[l] : m;
  return m;
}
/// The lanes of a comparison result as bits (lane l → bit l).
inline unsigned lane_bits(VecL m) {
#if defined(__AVX__)
  return static_cast<unsigned>(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
#else
  unsigned bits = 0;
  for (int l = 0; l < LANES; ++l) bits |= (m[l] != 0 ? 1u : 0u) << l;
  return bits;
#endif
}
/// Whether any lane of a comparison result is true.
inline bool any(VecL m) {
  return lane_bits(m) != 0;
}
/// The square root of a double, so that a kernel templated over its number type (double
/// or VecD) calls lanes::sqrt for both.
inline double sqrt(double x) {
  return __builtin_sqrt(x);
}
/// Lane-wise square root (the element-wise loop compiles to one vector instruction).
inline VecD sqrt(VecD v) {
#if defined(__AVX__)
  return reinterpret_cast<VecD>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(v)));
#else
  for (int l = 0; l < LANES; ++l) v[l] = __builtin_sqrt(v[l]);
  return v;
#endif
}

}  // namespace knit::lanes
