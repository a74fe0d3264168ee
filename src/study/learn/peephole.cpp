// One peephole LSTM layer's time loop, forward and backward, for study.model.PeepholeFunction.
//
// Compiled on first use by study/native.py (plain C++, no PyTorch headers, about a second) and called
// through ctypes with raw pointers to contiguous, time-major tensors. The recurrent matrix products
// go to the BLAS that PyTorch itself uses (its sgemm_/dgemm_, passed in as a function pointer); all
// the elementwise work of a step is one fused loop, instead of ten PyTorch kernels per step.
//
// Layout (row-major, as the PyTorch tensors): gates (T, B, 4H) in the order i, f, g, o; cell and
// hidden states (T + 1, B, H) with index 0 holding the initial state; weight_hh (4H, H).
// Gates (Gers et al. 2002, Sak et al. 2014; diagonal peepholes w_ci, w_cf, w_co):
//   i = s(W_i x + R_i h + w_ci c_old + b_i)    f = s(... + w_cf c_old)    g = tanh(...)
//   c = f c_old + i g                           o = s(... + w_co c)       h = o tanh(c)

#include "rnn_math.h"

template <typename R>
static void forward(int T, int B, int H, R* gates, const R* w_hh_t, const R* w_ci, const R* w_cf,
                    const R* w_co, R* cs, R* hs, R* tcs, void* blas) {
  const int H4 = 4 * H;
  for (int t = 0; t < T; ++t) {
    R* G = gates + (int64_t)t * B * H4;
    const R* h_old = hs + (int64_t)t * B * H;
    // G (B, 4H) += h_old (B, H) @ w_hh_t (H, 4H); column-major that is G^T += w_hh_t^T h_old^T, and
    // BLAS reads the row-major w_hh_t as that transpose without copying.
    gemm(blas, "N", "N", H4, B, H, R(1), w_hh_t, H4, h_old, H, R(1), G, H4);
    // Two passes over the batch, i, f, g and the new cell, then o and h: each is a long loop of
    // independent units, so the core overlaps many units' exp chains instead of waiting on one.
    const int64_t row0 = (int64_t)t * B * H;
    for (int b = 0; b < B; ++b) {
      R* g = G + (int64_t)b * H4;
      const R* c_old = cs + row0 + (int64_t)b * H;
      R* c_new = cs + row0 + (int64_t)(B + b) * H;
#pragma GCC ivdep
      for (int j = 0; j < H; ++j) {
        const R ci = c_old[j];
        const R i = sigmoid_(g[j] + w_ci[j] * ci);
        const R f = sigmoid_(g[H + j] + w_cf[j] * ci);
        const R gg = tanh_(g[2 * H + j]);
        g[j] = i;
        g[H + j] = f;
        g[2 * H + j] = gg;
        c_new[j] = f * ci + i * gg;
      }
    }
    for (int b = 0; b < B; ++b) {
      R* g = G + (int64_t)b * H4;
      const R* c_new = cs + row0 + (int64_t)(B + b) * H;
      R* h_new = hs + row0 + (int64_t)(B + b) * H;
      R* tc = tcs + row0 + (int64_t)b * H;
#pragma GCC ivdep
      for (int j = 0; j < H; ++j) {
        const R c = c_new[j];
        const R o = sigmoid_(g[3 * H + j] + w_co[j] * c);
        const R tcv = tanh_(c);
        g[3 * H + j] = o;
        tc[j] = tcv;
        h_new[j] = o * tcv;
      }
    }
  }
}

// d_out (T, B, H): dL/dh_t from above, time-major; overwritten (the recurrent products add into it).
// dh0, dc0 (B, H): in: dL/d(final h, c); out: dL/d(h0, c0). d_gates (T, B, 4H): out, dL/d(pre-activations).
// d_small (7H): out, the gradients of the small parameters, summed over time and batch while the loop
// has them at hand: peepholes w_ci, w_cf, w_co (3H), then the bias (4H, order i, f, g, o). Each step's
// batch sum is taken in R, the sum over steps in double.
template <typename R>
static void backward(int T, int B, int H, const R* gates, const R* cs, const R* tcs, const R* w_hh,
                     const R* w_ci, const R* w_cf, const R* w_co, R* d_out, R* dh0, R* dc0, R* d_gates,
                     R* d_small, void* blas) {
  const int H4 = 4 * H;
  const int64_t BH = (int64_t)B * H;
  R* dc = dc0;  // running dL/dc, updated in place step by step
  std::vector<R> step(7 * H);  // this step's batch sums: peepholes (3H), bias (4H)
  std::vector<double> total(7 * H, 0.0);
  R* s_peep = step.data();
  R* s_bias = s_peep + 3 * H;
  if (T > 0) {
    R* last = d_out + (T - 1) * BH;
    for (int64_t k = 0; k < BH; ++k) last[k] += dh0[k];
  }
  for (int t = T - 1; t >= 0; --t) {
    const R* dh = d_out + t * BH;
    const R* G = gates + (int64_t)t * B * H4;
    R* dG = d_gates + (int64_t)t * B * H4;
    std::fill(step.begin(), step.end(), R(0));
    for (int b = 0; b < B; ++b) {
      const R* g = G + (int64_t)b * H4;
      R* dg = dG + (int64_t)b * H4;
      const int64_t row = (int64_t)t * BH + (int64_t)b * H;
      const R* c_old = cs + row;
      const R* c_new = cs + row + BH;
      const R* tc = tcs + row;
      const R* dhb = dh + (int64_t)b * H;
      R* dcb = dc + (int64_t)b * H;
#pragma GCC ivdep
      for (int j = 0; j < H; ++j) {
        const R i = g[j], f = g[H + j], gg = g[2 * H + j], o = g[3 * H + j];
        const R tcv = tc[j], dhv = dhb[j], co = c_old[j];
        const R dgo = dhv * tcv * o * (R(1) - o);
        const R dcv = dcb[j] + dhv * o * (R(1) - tcv * tcv) + dgo * w_co[j];
        const R dgi = dcv * gg * i * (R(1) - i);
        const R dgf = dcv * co * f * (R(1) - f);
        const R dgg = dcv * i * (R(1) - gg * gg);
        dg[j] = dgi;
        dg[H + j] = dgf;
        dg[2 * H + j] = dgg;
        dg[3 * H + j] = dgo;
        dcb[j] = dcv * f + dgi * w_ci[j] + dgf * w_cf[j];
        s_peep[j] += dgi * co;
        s_peep[H + j] += dgf * co;
        s_peep[2 * H + j] += dgo * c_new[j];
        s_bias[j] += dgi;
        s_bias[H + j] += dgf;
        s_bias[2 * H + j] += dgg;
        s_bias[3 * H + j] += dgo;
      }
    }
    for (int k = 0; k < 7 * H; ++k) total[k] += step[k];
    // dL/dh_{t-1} = d_out[t-1] + dG (B, 4H) @ w_hh (4H, H); column-major: w_hh^T-as-stored times dG^T.
    R* target = t > 0 ? d_out + (t - 1) * BH : dh0;
    gemm(blas, "N", "N", H, B, H4, R(1), w_hh, H, dG, H4, t > 0 ? R(1) : R(0), target, H);
  }
  for (int k = 0; k < 7 * H; ++k) d_small[k] = R(total[k]);
}

extern "C" {
void peephole_forward_f32(int T, int B, int H, float* gates, const float* w_hh_t, const float* w_ci,
                          const float* w_cf, const float* w_co, float* cs, float* hs, float* tcs, void* blas) {
  forward<float>(T, B, H, gates, w_hh_t, w_ci, w_cf, w_co, cs, hs, tcs, blas);
}
void peephole_forward_f64(int T, int B, int H, double* gates, const double* w_hh_t, const double* w_ci,
                          const double* w_cf, const double* w_co, double* cs, double* hs, double* tcs,
                          void* blas) {
  forward<double>(T, B, H, gates, w_hh_t, w_ci, w_cf, w_co, cs, hs, tcs, blas);
}
void peephole_backward_f32(int T, int B, int H, const float* gates, const float* cs, const float* tcs,
                           const float* w_hh, const float* w_ci, const float* w_cf, const float* w_co,
                           float* d_out, float* dh0, float* dc0, float* d_gates, float* d_small, void* blas) {
  backward<float>(T, B, H, gates, cs, tcs, w_hh, w_ci, w_cf, w_co, d_out, dh0, dc0, d_gates, d_small, blas);
}
void peephole_backward_f64(int T, int B, int H, const double* gates, const double* cs, const double* tcs,
                           const double* w_hh, const double* w_ci, const double* w_cf, const double* w_co,
                           double* d_out, double* dh0, double* dc0, double* d_gates, double* d_small,
                           void* blas) {
  backward<double>(T, B, H, gates, cs, tcs, w_hh, w_ci, w_cf, w_co, d_out, dh0, dc0, d_gates, d_small, blas);
}
}
