// One GRU layer's time loop, forward and backward, for study.gru.GRUFunction: nn.GRU's equations
// (Cho et al. 2014, with the reset gate applied after the recurrent product, as cuDNN and PyTorch do):
//   r = s(W_ir x + b_ir + W_hr h + b_hr)      z = s(W_iz x + b_iz + W_hz h + b_hz)
//   n = tanh(W_in x + b_in + r (W_hn h + b_hn))                h' = (1 - z) n + z h
//
// Compiled with peephole.cpp into one library by study/native.py. Layout (row-major, time-major, as the
// PyTorch tensors): gates (T, B, 3H) in the order r, z, n; on entry the input projection with b_ih, and
// b_hr, b_hz already added; on exit the activated r, z, n. hn (T, B, H): out, W_hn h + b_hn of each step.
// hs (T + 1, B, H): index 0 holds the initial state. weight_hh (3H, H); its transpose w_hh_t (H, 3H).

#include "rnn_math.h"

// scratch (B, 3H): the step's recurrent product h W_hh^T.
template <typename R>
static void forward(int T, int B, int H, R* gates, const R* w_hh_t, const R* b_hn, R* hs, R* hn, R* scratch,
                    void* blas) {
  const int H3 = 3 * H;
  for (int t = 0; t < T; ++t) {
    R* G = gates + (int64_t)t * B * H3;
    const R* h_old = hs + (int64_t)t * B * H;
    // scratch (B, 3H) = h_old (B, H) @ w_hh_t (H, 3H); column-major: scratch^T = w_hh_t^T h_old^T.
    gemm(blas, "N", "N", H3, B, H, R(1), w_hh_t, H3, h_old, H, R(0), scratch, H3);
    for (int b = 0; b < B; ++b) {
      R* g = G + (int64_t)b * H3;
      const R* s = scratch + (int64_t)b * H3;
      const int64_t row = ((int64_t)t * B + b) * H;
      const R* ho = h_old + (int64_t)b * H;
      R* h_new = hs + row + (int64_t)B * H;
      R* hn_t = hn + row;
#pragma GCC ivdep
      for (int j = 0; j < H; ++j) {
        const R r = sigmoid_(g[j] + s[j]);
        const R z = sigmoid_(g[H + j] + s[H + j]);
        const R hnv = s[2 * H + j] + b_hn[j];
        const R n = tanh_(g[2 * H + j] + r * hnv);
        g[j] = r;
        g[H + j] = z;
        g[2 * H + j] = n;
        hn_t[j] = hnv;
        h_new[j] = n + z * (ho[j] - n);
      }
    }
  }
}

// d_out (T, B, H): dL/dh_t from above; overwritten (the recurrent terms add into it). dh0 (B, H): in,
// dL/d(final h); out, dL/dh0. d_x (T, B, 3H): out, dL/d(input projection), order r, z, n. d_s (T, B, 3H):
// out, dL/d(recurrent product W_hh h + b_hh), the same but the n part times r.
template <typename R>
static void backward(int T, int B, int H, const R* gates, const R* hs, const R* hn, const R* w_hh, R* d_out,
                     R* dh0, R* d_x, R* d_s, void* blas) {
  const int H3 = 3 * H;
  const int64_t BH = (int64_t)B * H;
  if (T > 0) {
    R* last = d_out + (T - 1) * BH;
    for (int64_t k = 0; k < BH; ++k) last[k] += dh0[k];
  }
  for (int t = T - 1; t >= 0; --t) {
    const R* dh = d_out + t * BH;
    R* target = t > 0 ? d_out + (t - 1) * BH : dh0;  // dL/dh_{t-1}: the direct path, then the product
    const bool add = t > 0;
    for (int b = 0; b < B; ++b) {
      const int64_t row = (int64_t)t * BH + (int64_t)b * H;
      const R* g = gates + (int64_t)(t * B + b) * H3;
      R* dx = d_x + (int64_t)(t * B + b) * H3;
      R* ds = d_s + (int64_t)(t * B + b) * H3;
      const R* ho = hs + row;
      const R* hnv = hn + row;
      const R* dhb = dh + (int64_t)b * H;
      R* tg = target + (int64_t)b * H;
#pragma GCC ivdep
      for (int j = 0; j < H; ++j) {
        const R r = g[j], z = g[H + j], n = g[2 * H + j], dhv = dhb[j];
        const R dan = dhv * (R(1) - z) * (R(1) - n * n);
        const R daz = dhv * (ho[j] - n) * z * (R(1) - z);
        const R dar = dan * hnv[j] * r * (R(1) - r);
        dx[j] = dar;
        dx[H + j] = daz;
        dx[2 * H + j] = dan;
        ds[j] = dar;
        ds[H + j] = daz;
        ds[2 * H + j] = dan * r;
        tg[j] = (add ? tg[j] : R(0)) + dhv * z;
      }
    }
    // dL/dh_{t-1} += d_s[t] (B, 3H) @ w_hh (3H, H); column-major: w_hh^T-as-stored times d_s^T.
    gemm(blas, "N", "N", H, B, H3, R(1), w_hh, H, d_s + (int64_t)t * B * H3, H3, R(1), target, H);
  }
}

extern "C" {
void gru_forward_f32(int T, int B, int H, float* gates, const float* w_hh_t, const float* b_hn, float* hs,
                     float* hn, float* scratch, void* blas) {
  forward<float>(T, B, H, gates, w_hh_t, b_hn, hs, hn, scratch, blas);
}
void gru_forward_f64(int T, int B, int H, double* gates, const double* w_hh_t, const double* b_hn, double* hs,
                     double* hn, double* scratch, void* blas) {
  forward<double>(T, B, H, gates, w_hh_t, b_hn, hs, hn, scratch, blas);
}
void gru_backward_f32(int T, int B, int H, const float* gates, const float* hs, const float* hn,
                      const float* w_hh, float* d_out, float* dh0, float* d_x, float* d_s, void* blas) {
  backward<float>(T, B, H, gates, hs, hn, w_hh, d_out, dh0, d_x, d_s, blas);
}
void gru_backward_f64(int T, int B, int H, const double* gates, const double* hs, const double* hn,
                      const double* w_hh, double* d_out, double* dh0, double* d_x, double* d_s, void* blas) {
  backward<double>(T, B, H, gates, hs, hn, w_hh, d_out, dh0, d_x, d_s, blas);
}
}
