// Shared by the compiled recurrent loops (peephole.cpp, gru.cpp): the BLAS call and the activations.
//
// gemm goes to the BLAS that PyTorch itself uses (its Fortran sgemm_/dgemm_, passed in as a function
// pointer by study/native.py). exp_, sigmoid_ and tanh_ are written so that the compiler vectorises the
// elementwise loops that call them (no libm call in float32).

#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>
#include <algorithm>

typedef void (*sgemm_t)(const char*, const char*, const int*, const int*, const int*, const float*,
                        const float*, const int*, const float*, const int*, const float*, float*, const int*);
typedef void (*dgemm_t)(const char*, const char*, const int*, const int*, const int*, const double*,
                        const double*, const int*, const double*, const int*, const double*, double*,
                        const int*);

static inline void gemm(void* f, const char* ta, const char* tb, int m, int n, int k, float alpha,
                        const float* a, int lda, const float* b, int ldb, float beta, float* c, int ldc) {
  ((sgemm_t)f)(ta, tb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}
static inline void gemm(void* f, const char* ta, const char* tb, int m, int n, int k, double alpha,
                        const double* a, int lda, const double* b, int ldb, double beta, double* c, int ldc) {
  ((dgemm_t)f)(ta, tb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}

// exp for float in a form the compiler vectorises: e^x = 2^n e^r, |r| <= ln2 / 2, with Cephes' expf
// polynomial (relative error about 1e-7). n = rint(x / ln2) is a vector rounding instruction (no libm call
// with -fno-math-errno) and stays exact when the compiler may reassociate (-funsafe-math-optimizations).
static inline float exp_(float x) {
  x = std::fmin(std::fmax(x, -87.0f), 88.0f);
  const float n = std::rint(x * 1.44269504088896341f);
  const int32_t scale_bits = ((int32_t)n + 127) << 23;
  float scale;
  std::memcpy(&scale, &scale_bits, 4);
  float r = x - n * 0.693359375f;
  r = r + n * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  return (p * r * r + r + 1.0f) * scale;
}
static inline double exp_(double x) { return std::exp(x); }  // float64 is for tests: exact libm

template <typename R> static inline R sigmoid_(R x) { return R(1) / (R(1) + exp_(-x)); }
template <typename R> static inline R tanh_(R x) { return R(1) - R(2) / (exp_(R(2) * x) + R(1)); }

