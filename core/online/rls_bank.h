#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/numerics/lane_vectors.h"
#include "core/online/rls.h"

namespace canalid::core {

/// The instruction set of RlsBank's structure-of-arrays update.
enum class RlsBankIsa {
  kBest,      ///< AVX-512VL where the CPU has it, else AVX2 where it has that, else the baseline
  kBaseline,  ///< SSE2, the baseline x86-64 ISA (two lanes per operation)
  kAvx2,      ///< AVX2, four lanes per operation
  /// AVX2's four lanes per operation compiled for AVX-512VL: 32 vector registers instead of 16,
  /// so that most of the update's live values stay in registers (the AVX2 code spills them)
  kAvx512,
};

/// `lanes` estimators Rls<N> with the same options, updated together: one output y per sample
/// and one regressor per lane (a delay bank's candidates).  Each lane is bit for bit the Rls<N>
/// it replaces: the same operations in the same order on the same numbers.
///
/// With a UD method (kUdDirectional, the default, or kUdExponential) and no innovation guard
/// (reject, huber, dead_zone, cusum_threshold), the lanes are stored as structure of arrays in
/// blocks of kBlock: every lane's U, D, theta, noise sums and counts side by side, one update
/// for all, the per-lane branches of Rls::Update (invalid samples, freeze, directional
/// forgetting's r > 1 - lambda) taken as masks; the box and the trace bounds, off by default,
/// go lane by lane after it.  Otherwise each lane is an Rls<N> of its own (the same results,
/// no speed-up).  What an update costs is its operation count, each operation serving the two
/// lanes of an SSE2 register (the baseline x86-64 ISA) or, where the CPU has AVX2, the four of
/// an AVX2 register (chosen at run time; with AVX-512VL the same four-lane code has twice the
/// registers; none contracts to FMA, the build forbids it, so each is Rls bit for bit).  Keeping
/// Rls's results bit for bit keeps its bookkeeping (counts, last error, outcome) per lane, and
/// every branch becomes a select (docs/performance.md); a block whose lanes all take Bierman's
/// update (the usual sample) stores its results without the selects. Allocates only in the
/// constructor; Update and the accessors never allocate. Deterministic.  Not thread-safe (Lane()
/// uses a scratch estimator).
template <int N>
class RlsBank final {
  static_assert(N != Eigen::Dynamic, "RlsBank needs a fixed parameter count");

 public:
  static constexpr int kBlock = 4;  // lanes per block: one AVX2 register, two SSE2 ones
  using Matrix = Eigen::Matrix<double, N, N>;
  /// The regressors of one sample, phi_i of lane l at (i, l); lanes() columns and padding.
  using Regressors = Eigen::Matrix<double, N, Eigen::Dynamic, Eigen::RowMajor>;
  using Result = typename Rls<N>::Result;

  /// `isa`: kBest takes the best the CPU has; kBaseline keeps to SSE2; kAvx2 and kAvx512 insist.
  /// @throws std::invalid_argument on a bad option (RlsOptions::Validate), lanes < 1, or kAvx2
  /// (kAvx512) on a CPU without AVX2 (AVX-512F and AVX-512VL).
  RlsBank(const RlsOptions& options, int lanes, RlsBankIsa isa = RlsBankIsa::kBest);

  int lanes() const { return lanes_; }
  /// The instruction set the structure-of-arrays update runs on (kBaseline, kAvx2 or kAvx512).
  RlsBankIsa isa() const { return isa_; }
  /// Whether the lanes run as structure of arrays (a UD method without innovation guards).
  bool structure_of_arrays() const { return soa_; }
  /// Fill column l with lane l's regressor before Update.
  Regressors& regressors() { return phi_; }
  /// One sample on every lane: as Rls<N>::Update(regressors().col(l), y) for each lane l.
  void Update(double y);
  /// Update(y), then ResidualLosses(nonnegative, losses), in one pass over the blocks: each
  /// block's losses from its new state while that is at hand.  The same numbers as the two
  /// calls.  @pre losses.size() >= lanes().
  void UpdateWithLosses(double y, int nonnegative, std::span<double> losses);
  /// What Update did on lane l.
  Result result(int lane) const;

  double theta(int lane, int i) const;
  double residual_sum_of_squares(int lane) const;
  /// P_ii of lane l (relative to sigma2), as Rls::CovarianceDiagonal.
  double CovarianceDiagonal(int lane, int i) const;
  /// Every lane's least-squares loss into losses[0, lanes()): its residual sum of squares, or
  /// with `nonnegative` = i in [0, N) that of its fit constrained to theta_i >= 0: for a lane
  /// whose theta_i is negative and P_ii > 0, plus theta_i^2 / P_ii (the fit with theta_i = 0,
  /// P relative to sigma2).  Per lane the arithmetic of residual_sum_of_squares, theta and
  /// CovarianceDiagonal, bit for bit; all lanes of a block at once.  @pre losses.size() >= lanes().
  void ResidualLosses(int nonnegative, std::span<double> losses) const;
  /// Lane l as an Rls<N>: a copy of its state in a scratch estimator, valid until the next call
  /// of Lane() or any non-const member.
  const Rls<N>& Lane(int lane) const;
  /// Rls::Transform on lane l.
  void Transform(int lane, const Matrix& t);

 private:
  static constexpr std::size_t kN = N;  // array extents are unsigned
  static constexpr std::size_t kLanes = kBlock;
  using Field = double[kLanes];  // one number of each lane of a block
  static constexpr std::size_t kUpper = kN > 1 ? kN*(kN - 1) / 2 : 1;
  /// Where u_ij, i < j, is kept: column by column.
  static constexpr std::size_t Upper(std::size_t i, std::size_t j) { return j * (j - 1) / 2 + i; }
  struct alignas(kBlock * sizeof(double)) Block {
    Field u[kUpper];  // U's strictly upper triangle, u_ij at Upper(i, j) (U's diagonal is 1)
    Field d[kN];
    Field theta[kN];
    Field ssr;
    Field weight;
    // Rls's bookkeeping, kept here so that the update writes it lane-wise (counts as doubles:
    // exact to 2^53).  Not kept, being known from the rest: Rls's accepted samples (without
    // innovation guards, updates + frozen_count) and the last result's prediction error (the
    // last error, or NaN when the last sample was rejected).
    Field updates;
    Field frozen_count;
    Field rejected_invalid;
    Field last_error;  // of the last valid sample
    Field excitation;  // r of the last valid sample
    Field norm2;       // ||phi||^2 of the last valid sample
    Field frozen;      // 1: the last valid sample froze the lane
    Field outcome;     // the last Update's RlsOutcome
  };
  // The rest of a lane's Rls state (only the box and the trace bounds change it).
  struct LaneState {
    bool bounded = false;
    std::int64_t projections = 0;
    std::int64_t trace_bounded = 0;
  };

  static std::size_t Index(int lane) { return static_cast<std::size_t>(lane); }
  // Lanes at..at+W-1 of a field as one W-lane value (GCC gives vector types their element's
  // alias set; `at` is a multiple of W, so the value is aligned).
  template <class V>
  [[gnu::always_inline]] static V& At(Field& field, std::size_t at) {
    return *reinterpret_cast<V*>(&field[at]);
  }
  template <class V>
  [[gnu::always_inline]] static const V& At(const Field& field, std::size_t at) {
    return *reinterpret_cast<const V*>(&field[at]);
  }
  // The helpers take vectors by reference: a 32-byte vector passed or returned by value makes
  // GCC warn (-Wpsabi) that the ABI differs where AVX is off, even when always inlined.
  // GCC folds bit operations on a comparison's mask back into a ?: (and then, for 64-bit masks
  // on SSE2, goes lane by lane in scalar code): an empty asm hides where the mask comes from.
  // A code-generation hint for GCC, the compiler of record; clang (which only parses here, for
  // clang-tidy) rejects a 32-byte register operand outside AVX code, so it does without.
  template <class M>
  [[gnu::always_inline]] static void Hide(M& mask) {
#ifndef __clang__
    __asm__("" : "+v"(mask));  // "v": any vector register the ISA has (32 with AVX-512VL)
#else
    (void)mask;
#endif
  }
  /// target = a in the lanes where the mask is set, in bit operations (the vector extension's
  /// own ?: compares the mask with 0 in 64-bit integers, which SSE2 does not have).
  template <class M, class L>
  [[gnu::always_inline]] static void Assign(const M& mask, const L& a, L& target) {
    M m = mask;
    Hide(m);
    target = __builtin_bit_cast(
        L, (__builtin_bit_cast(M, a) & m) | (__builtin_bit_cast(M, target) & ~m));
  }
  /// Whether every lane of the mask is set.
  template <class M>
  [[gnu::always_inline]] static bool AllSet(const M& mask) {
    std::int64_t lanes[sizeof(M) / sizeof(std::int64_t)];
    __builtin_memcpy(&lanes, &mask, sizeof(M));
    std::int64_t all = -1;
    for (const std::int64_t lane : lanes) all &= lane;
    return all == -1;
  }
  /// counter += 1 in the lanes where the mask is set.
  template <class M, class L>
  [[gnu::always_inline]] static void CountWhere(const M& mask, L& counter) {
    L add{};
    Assign(mask, add + 1.0, add);
    counter += add;
  }
  /// ResidualLosses' `nonnegative` as LossLanes takes it: -1 for none.
  static int ConstrainedIndex(int nonnegative) {
    return nonnegative >= 0 && nonnegative < N ? nonnegative : -1;
  }
  template <int W>
  [[gnu::always_inline]] void UpdateLanes(Block& s, std::size_t at, int first_lane, double y);
  // Every block updated with W lanes an operation, each followed by the bounds (if any) and,
  // where `losses` is not null, by its losses (LossBlock).
  template <int W>
  [[gnu::always_inline]] void UpdateBlocks(double y, int constrained, double* losses);
  void UpdateBlocksBaseline(double y, int constrained, double* losses);
  template <int W>
  [[gnu::always_inline]] void LossLanes(const Block& s, std::size_t at, int constrained,
                                        double* out) const;
  // Block b's losses into losses[b * kBlock, ...) (its lanes below lanes()).
  template <int W>
  [[gnu::always_inline]] void LossBlock(std::size_t b, int constrained, double* losses) const;
  [[gnu::target("avx2,no-fma")]] void LossesAvx2(int constrained, double* losses) const;
  // Compiled for AVX2 alone, called only where the CPU has it.  "no-fma": no contraction of
  // a * b + c, which would round differently from Rls.  (Eight lanes an AVX-512 register were
  // tried: GCC 12 compares those vectors lane by lane, 1.5 x slower than AVX2.)
  [[gnu::target("avx2,no-fma")]] void UpdateBlocksAvx2(double y, int constrained, double* losses);
  // The same four-lane update compiled for AVX-512VL (its 32 vector registers), called only
  // where the CPU has AVX-512F and AVX-512VL.  AVX-512F brings FMA instructions of its own that
  // "no-fma" does not remove: the build's -ffp-contract=off (CMakeLists.txt) keeps a * b + c two
  // roundings, as in Rls.
  [[gnu::target("avx2,avx512f,avx512vl")]] void UpdateBlocksAvx512(double y, int constrained,
                                                                   double* losses);
  // Whether Update rejects y on every lane (Rls::Update's output check).
  bool OutputInvalid(double y) const {
    return !std::isfinite(y) || std::abs(y) > options_.output_abs_max;
  }
  void RejectOutput();
  // The structure-of-arrays update of a valid y on the CPU's ISA (losses as UpdateBlocks).
  void UpdateValid(double y, int constrained, double* losses);
  // The box and the trace bounds on the block's lanes that updated, lane by lane.
  void BoundLanes(Block& s, int first_lane);
  void Load(int lane, Rls<N>& into) const;
  void Store(int lane, const Rls<N>& from);

  RlsOptions options_;
  int lanes_;
  bool soa_ = false;
  RlsBankIsa isa_ = RlsBankIsa::kBaseline;
  double lambda_ = 1.0;
  double noise_forgetting_ = 1.0;
  bool has_box_ = false;
  bool trace_bounds_ = false;
  Eigen::Matrix<double, N, 1> lower_;
  Eigen::Matrix<double, N, 1> upper_;
  Regressors phi_;
  std::vector<Block> blocks_;
  std::vector<LaneState> state_;
  std::vector<Result> results_;  // !soa_
  std::vector<Rls<N>> scalar_;   // !soa_: the lanes themselves
  mutable Rls<N> scratch_;       // Lane()'s copy
};

// ---------------------------------------------------------------------------------------------
// Implementation (a template on N, so it lives in the header).

template <int N>
RlsBank<N>::RlsBank(const RlsOptions& options, int lanes, RlsBankIsa isa)
    : options_(options), lanes_(lanes), scratch_(options) {
  if (lanes < 1) {
    throw std::invalid_argument("RlsBank: " + std::to_string(lanes) + " lanes; at least 1");
  }
  // Rls's own members, copied from the scratch estimator built from the same options (so that
  // the rules deciding them stay Rls's).
  const bool ud =
      options.method == RlsMethod::kUdDirectional || options.method == RlsMethod::kUdExponential;
  soa_ = ud && !scratch_.guards_;
  const bool avx2 = __builtin_cpu_supports("avx2") != 0;
  const bool avx512 =
      avx2 && __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0;
  if (isa == RlsBankIsa::kAvx2 && !avx2) {
    throw std::invalid_argument("RlsBank: AVX2 asked for; this CPU does not have it");
  }
  if (isa == RlsBankIsa::kAvx512 && !avx512) {
    throw std::invalid_argument(
        "RlsBank: AVX-512VL asked for; this CPU does not have AVX-512F and AVX-512VL");
  }
  if (soa_ && (isa == RlsBankIsa::kAvx512 || (isa == RlsBankIsa::kBest && avx512))) {
    isa_ = RlsBankIsa::kAvx512;
  } else if (soa_ && isa != RlsBankIsa::kBaseline && avx2) {
    isa_ = RlsBankIsa::kAvx2;
  }
  lambda_ = scratch_.GainForgetting();
  noise_forgetting_ = scratch_.noise_forgetting_;
  has_box_ = scratch_.has_box_;
  lower_ = scratch_.lower_;
  upper_ = scratch_.upper_;
  trace_bounds_ = std::isfinite(options.trace_max) || options.trace_min > 0.0;
  const int padded = (lanes + kBlock - 1) / kBlock * kBlock;
  phi_.setZero(N, padded);
  if (!soa_) {
    results_.assign(Index(lanes),
                    Result{std::numeric_limits<double>::quiet_NaN(), RlsOutcome::kRejectedInvalid});
    scalar_.assign(Index(lanes), scratch_);
    return;
  }
  blocks_.resize(static_cast<std::size_t>(padded / kBlock));
  state_.assign(Index(lanes), LaneState{});
  for (int l = 0; l < padded; ++l) Store(l, scratch_);  // padding lanes too: defined numbers
}

template <int N>
void RlsBank<N>::Store(int lane, const Rls<N>& from) {
  Block& s = blocks_[Index(lane / kBlock)];
  const auto l = static_cast<std::size_t>(lane % kBlock);
  for (std::size_t i = 0; i < kN; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = i + 1; j < kN; ++j) {
      s.u[Upper(i, j)][l] = from.u_(ii, static_cast<Eigen::Index>(j));
    }
    s.d[i][l] = from.d_(ii);
    s.theta[i][l] = from.theta_(ii);
  }
  s.ssr[l] = from.ssr_;
  s.weight[l] = from.weight_;
  const RlsHealth& h = from.health_;
  s.updates[l] = static_cast<double>(h.updates);
  s.frozen_count[l] = static_cast<double>(h.frozen_count);
  s.rejected_invalid[l] = static_cast<double>(h.rejected_invalid);
  s.last_error[l] = from.last_error_;
  s.excitation[l] = h.excitation;
  s.norm2[l] = h.regressor_norm2;
  s.frozen[l] = h.frozen ? 1.0 : 0.0;
  s.outcome[l] = static_cast<double>(RlsOutcome::kRejectedInvalid);
  if (lane >= lanes_) return;  // padding: no lane state
  LaneState& st = state_[Index(lane)];
  st.bounded = from.bounded_;
  st.projections = h.projections;
  st.trace_bounded = h.trace_bounded;
}

template <int N>
void RlsBank<N>::Load(int lane, Rls<N>& into) const {
  const Block& s = blocks_[Index(lane / kBlock)];
  const auto l = static_cast<std::size_t>(lane % kBlock);
  for (std::size_t i = 0; i < kN; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < kN; ++j) {
      const auto jj = static_cast<Eigen::Index>(j);
      into.u_(ii, jj) = j > i ? s.u[Upper(i, j)][l] : j == i ? 1.0 : 0.0;
    }
    into.d_(ii) = s.d[i][l];
    into.theta_(ii) = s.theta[i][l];
  }
  into.ssr_ = s.ssr[l];
  into.weight_ = s.weight[l];
  into.accepted_ = static_cast<long long>(s.updates[l] + s.frozen_count[l]);
  into.last_error_ = s.last_error[l];
  const LaneState& st = state_[Index(lane)];
  into.bounded_ = st.bounded;
  RlsHealth h;  // no innovation guard: their counts stay 0
  h.excitation = s.excitation[l];
  h.regressor_norm2 = s.norm2[l];
  // Rls sets it with each noise update, from the same sums.
  h.innovation_variance = s.ssr[l] / std::max(s.weight[l] - N, 1.0);
  h.frozen = s.frozen[l] != 0.0;
  h.updates = static_cast<std::int64_t>(s.updates[l]);
  h.rejected_invalid = static_cast<std::int64_t>(s.rejected_invalid[l]);
  h.frozen_count = static_cast<std::int64_t>(s.frozen_count[l]);
  h.projections = st.projections;
  h.trace_bounded = st.trace_bounded;
  into.health_ = h;
}

template <int N>
inline typename RlsBank<N>::Result RlsBank<N>::result(int lane) const {
  if (!soa_) return results_[Index(lane)];
  const Block& s = blocks_[Index(lane / kBlock)];
  const auto l = static_cast<std::size_t>(lane % kBlock);
  const auto outcome = static_cast<RlsOutcome>(static_cast<int>(s.outcome[l]));
  return {outcome == RlsOutcome::kRejectedInvalid ? std::numeric_limits<double>::quiet_NaN()
                                                  : s.last_error[l],
          outcome};
}

template <int N>
const Rls<N>& RlsBank<N>::Lane(int lane) const {
  if (!soa_) return scalar_[Index(lane)];
  Load(lane, scratch_);
  return scratch_;
}

template <int N>
void RlsBank<N>::Transform(int lane, const Matrix& t) {
  if (!soa_) {
    scalar_[Index(lane)].Transform(t);
    return;
  }
  const RlsOutcome last = result(lane).outcome;  // Store() does not know it
  Load(lane, scratch_);
  scratch_.Transform(t);
  Store(lane, scratch_);
  Block& s = blocks_[Index(lane / kBlock)];
  s.outcome[lane % kBlock] = static_cast<double>(last);
}

template <int N>
inline double RlsBank<N>::theta(int lane, int i) const {
  if (!soa_) return scalar_[Index(lane)].theta()(i);
  return blocks_[Index(lane / kBlock)].theta[Index(i)][Index(lane % kBlock)];
}

template <int N>
inline double RlsBank<N>::residual_sum_of_squares(int lane) const {
  if (!soa_) return scalar_[Index(lane)].residual_sum_of_squares();
  return blocks_[Index(lane / kBlock)].ssr[Index(lane % kBlock)];
}

template <int N>
inline double RlsBank<N>::CovarianceDiagonal(int lane, int i) const {
  if (!soa_) return scalar_[Index(lane)].CovarianceDiagonal(i);
  const Block& s = blocks_[Index(lane / kBlock)];
  const std::size_t l = Index(lane % kBlock), ii = Index(i);
  double pii = 0.0;               // Rls::CovarianceDiagonal's sum, in its order
  pii += 1.0 * 1.0 * s.d[ii][l];  // u_ii = 1
  for (std::size_t j = ii + 1; j < kN; ++j) {
    pii += s.u[Upper(ii, j)][l] * s.u[Upper(ii, j)][l] * s.d[j][l];
  }
  return pii;
}

template <int N>
void RlsBank<N>::ResidualLosses(int nonnegative, std::span<double> losses) const {
  const bool constrain = nonnegative >= 0 && nonnegative < N;
  if (!soa_) {
    for (int l = 0; l < lanes_; ++l) {
      double loss = residual_sum_of_squares(l);
      if (constrain && theta(l, nonnegative) < 0.0) {
        const double t = theta(l, nonnegative), pii = CovarianceDiagonal(l, nonnegative);
        if (pii > 0.0) loss = loss + t * t / pii;
      }
      losses[Index(l)] = loss;
    }
    return;
  }
  const int constrained = ConstrainedIndex(nonnegative);
  if (isa_ != RlsBankIsa::kBaseline) {  // AVX2, or AVX-512VL (the losses need no more registers)
    LossesAvx2(constrained, losses.data());
  } else {
    for (std::size_t b = 0; b < blocks_.size(); ++b) LossBlock<2>(b, constrained, losses.data());
  }
}

template <int N>
void RlsBank<N>::LossesAvx2(int constrained, double* losses) const {
  for (std::size_t b = 0; b < blocks_.size(); ++b) LossBlock<4>(b, constrained, losses);
}

template <int N>
template <int W>
inline void RlsBank<N>::LossBlock(std::size_t b, int constrained, double* losses) const {
  const std::size_t first = b * kLanes;
  const std::size_t count = std::min(kLanes, Index(lanes_) - first);
  if (count == kLanes) {  // straight into losses
    for (std::size_t at = 0; at < kLanes; at += W) {
      LossLanes<W>(blocks_[b], at, constrained, losses + first);
    }
    return;
  }
  double out[kLanes];  // the last block's padding lanes have no place in losses
  for (std::size_t at = 0; at < kLanes; at += W) LossLanes<W>(blocks_[b], at, constrained, out);
  for (std::size_t l = 0; l < count; ++l) losses[first + l] = out[l];
}

template <int N>
template <int W>
inline void RlsBank<N>::LossLanes(const Block& s, std::size_t at, int constrained,
                                  double* out) const {
  // ResidualLosses' arithmetic on lanes at..at+W-1, CovarianceDiagonal's sum in its order.
  using Lanes = typename LaneVectors<W>::Lanes;
  using Mask = typename LaneVectors<W>::Mask;
  Lanes loss = At<Lanes>(s.ssr, at);
  if (constrained >= 0) {
    const Lanes zero{};
    const auto ii = static_cast<std::size_t>(constrained);
    Lanes pii = zero;
    pii += At<Lanes>(s.d[ii], at);  // u_ii = 1
#pragma GCC unroll 16
    for (std::size_t j = 1; j < kN; ++j) {
      if (j <= ii) continue;
      const Lanes u = At<Lanes>(s.u[Upper(ii, j)], at);
      pii += u * u * At<Lanes>(s.d[j], at);
    }
    const Lanes t = At<Lanes>(s.theta[ii], at);
    Mask penalised = (t < zero) & (pii > zero);
    Hide(penalised);
    Assign(penalised, loss + t * t / pii, loss);
  }
  __builtin_memcpy(out + at, &loss, sizeof(Lanes));
}

template <int N>
void RlsBank<N>::Update(double y) {
  if (!soa_) {
    for (int l = 0; l < lanes_; ++l) {
      // A contiguous copy: Eigen's products over a strided column round differently.
      const Eigen::Matrix<double, N, 1> phi = phi_.col(l);
      results_[Index(l)] = scalar_[Index(l)].Update(phi, y);
    }
    return;
  }
  if (OutputInvalid(y)) {
    RejectOutput();
    return;
  }
  UpdateValid(y, -1, nullptr);
}

template <int N>
void RlsBank<N>::UpdateWithLosses(double y, int nonnegative, std::span<double> losses) {
  if (!soa_ || OutputInvalid(y)) {
    Update(y);
    ResidualLosses(nonnegative, losses);
    return;
  }
  UpdateValid(y, ConstrainedIndex(nonnegative), losses.data());
}

template <int N>
void RlsBank<N>::RejectOutput() {
  for (Block& s : blocks_) {
    for (std::size_t l = 0; l < kLanes; ++l) {
      s.rejected_invalid[l] += 1.0;
      s.outcome[l] = static_cast<double>(RlsOutcome::kRejectedInvalid);
    }
  }
}

template <int N>
void RlsBank<N>::UpdateValid(double y, int constrained, double* losses) {
  if (isa_ == RlsBankIsa::kAvx512) {
    UpdateBlocksAvx512(y, constrained, losses);
  } else if (isa_ == RlsBankIsa::kAvx2) {
    UpdateBlocksAvx2(y, constrained, losses);
  } else {
    UpdateBlocksBaseline(y, constrained, losses);
  }
}

template <int N>
template <int W>
inline void RlsBank<N>::UpdateBlocks(double y, int constrained, double* losses) {
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    Block& s = blocks_[b];
    const int first_lane = static_cast<int>(b) * kBlock;
    for (std::size_t at = 0; at < kLanes; at += W) {
      UpdateLanes<W>(s, at, first_lane + static_cast<int>(at), y);
    }
    if (has_box_ || trace_bounds_) BoundLanes(s, first_lane);
    if (losses != nullptr) LossBlock<W>(b, constrained, losses);
  }
}

template <int N>
void RlsBank<N>::UpdateBlocksBaseline(double y, int constrained, double* losses) {
  UpdateBlocks<2>(y, constrained, losses);
}

// AVX2 and AVX-512VL code in a header: these two functions alone are compiled for those ISAs
// (UpdateBlocks, UpdateLanes, LossBlock and the helpers with vector operands are always inlined
// into them) and run only where __builtin_cpu_supports said yes.  What they call out of line
// (BoundLanes, Eigen's accessors) is compiled for the baseline, as everywhere else.
template <int N>
void RlsBank<N>::UpdateBlocksAvx2(double y, int constrained, double* losses) {
  UpdateBlocks<4>(y, constrained, losses);
}

template <int N>
void RlsBank<N>::UpdateBlocksAvx512(double y, int constrained, double* losses) {
  UpdateBlocks<4>(y, constrained, losses);
}

template <int N>
template <int W>
inline void RlsBank<N>::UpdateLanes(Block& s, std::size_t at, int first_lane, double y) {
  // Rls::Update on lanes at..at+W-1 of the block at once, each lane's arithmetic Rls's,
  // operation for operation; its branches are masks.
  using Lanes = typename LaneVectors<W>::Lanes;
  using Mask = typename LaneVectors<W>::Mask;
  const double lambda = lambda_;
  const bool exponential = options_.method == RlsMethod::kUdExponential;
  // (A vector plus a double adds the double to every lane: zero + x is x in every lane.)
  const Lanes zero{};
  const Lanes one = zero + 1.0;
  const Lanes largest = (zero + std::numeric_limits<double>::max());
  const Lanes regressor_max =
      (zero + std::min(options_.regressor_abs_max, std::numeric_limits<double>::max()));
  const Lanes forget = (zero + 1.0 - lambda);
  Lanes phi[kN];
#pragma GCC unroll 16
  for (std::size_t i = 0; i < kN; ++i) {
    __builtin_memcpy(&phi[i], phi_.row(static_cast<Eigen::Index>(i)).data() + first_lane,
                     sizeof(Lanes));
  }
  // Validity (NaN compares false), ||phi||^2, the a-priori error, f = U' phi, g = D f, r = f' g.
  Mask valid = (zero == zero);
  Lanes norm2 = zero, prediction = zero, r = zero;
#pragma GCC unroll 16
  for (std::size_t i = 0; i < kN; ++i) {
    valid &= (phi[i] <= regressor_max) & (phi[i] >= -regressor_max);
    norm2 += phi[i] * phi[i];
  }
#pragma GCC unroll 16
  for (std::size_t i = 0; i < kN; ++i) prediction += phi[i] * At<Lanes>(s.theta[i], at);
  const Lanes e = (zero + y) - prediction;
  Lanes f[kN], g[kN];
#pragma GCC unroll 16
  for (std::size_t j = 0; j < kN; ++j) {
    Lanes fj = phi[j];
#pragma GCC unroll 16
    for (std::size_t i = 0; i < j; ++i) fj += At<Lanes>(s.u[Upper(i, j)], at) * phi[i];
    f[j] = fj;
    g[j] = At<Lanes>(s.d[j], at) * fj;
    r += fj * g[j];
  }
  valid &= (e <= largest) & (e >= -largest) & (r >= zero) & (r <= largest);
  Hide(valid);
  Mask frozen = valid & ((norm2 <= (zero + options_.regressor_norm_min)) |
                         (r <= (zero + options_.excitation_min)));
  Hide(frozen);
  Mask apply = valid & ~frozen;
  Hide(apply);
  // Directional forgetting: Bierman's update when r > 1 - lambda, else the gain alone (lanes
  // that do not take the factors compute them with a variance of 1, then drop them).
  Mask bierman = exponential ? valid | ~valid : (r > forget);
  Hide(bierman);
  const Mask factors = apply & bierman;
  // Without forgetting (lambda = 1, the default) three of the divisions, the update's costliest
  // operations, have known quotients: r / 1 is r, and r / (r - 0) is 1 in every lane whose
  // result is kept (r finite and > 0; others are invalid or not Bierman's).  Same bits as Rls.
  const bool no_forgetting = lambda == 1.0;
  Lanes measurement = zero + lambda;
  if (!exponential) {
    measurement = one;
    if (!no_forgetting) Assign(bierman, r / (r - forget), measurement);
  }
  const Lanes scale = no_forgetting ? one + r : one + r / (zero + lambda);
  const Lanes step = e / ((zero + lambda) + r);
  // Bierman's measurement update (Rls::UpdateUdFactors) into new U, D and the gain numerator
  // k = P phi.  For directional forgetting's gain-only lanes Rls sums U g as
  // 0 + 1 g_i + sum_{j > i} u_ij g_j: the accumulator k holds the same sums in the same order.
  const bool divide_d = exponential && lambda != 1.0;  // D / lambda (exponential forgetting)
  Lanes alpha[kN], inv_alpha[kN];
  Lanes running = measurement;
#pragma GCC unroll 16
  for (std::size_t j = 0; j < kN; ++j) {
    running += f[j] * g[j];
    alpha[j] = running;
    inv_alpha[j] = one / running;
  }
  Lanes alpha_prev = measurement, inv_prev = no_forgetting ? one : one / measurement;
  Lanes k[kN], nu[kN][kN], nd[kN];
#pragma GCC unroll 16
  for (std::size_t j = 0; j < kN; ++j) {
    nd[j] = At<Lanes>(s.d[j], at) * (alpha_prev * inv_alpha[j]);
    const Lanes pj = -f[j] * inv_prev;
#pragma GCC unroll 16
    for (std::size_t i = 0; i < j; ++i) {
      const Lanes uij = At<Lanes>(s.u[Upper(i, j)], at);
      nu[i][j] = uij + k[i] * pj;
      k[i] += uij * g[j];
    }
    k[j] = g[j];
    alpha_prev = alpha[j];
    inv_prev = inv_alpha[j];
  }
  if (AllSet(factors)) {
    // Every lane takes Bierman's update (the usual sample): what the selects below give then,
    // without them.
#pragma GCC unroll 16
    for (std::size_t i = 0; i < kN; ++i) At<Lanes>(s.theta[i], at) += k[i] * step;
#pragma GCC unroll 16
    for (std::size_t j = 0; j < kN; ++j) {
      At<Lanes>(s.d[j], at) = divide_d ? nd[j] / (zero + lambda) : nd[j];
#pragma GCC unroll 16
      for (std::size_t i = 0; i < j; ++i) At<Lanes>(s.u[Upper(i, j)], at) = nu[i][j];
    }
    const Lanes nf = (zero + noise_forgetting_);
    At<Lanes>(s.ssr, at) = nf * At<Lanes>(s.ssr, at) + e * e / scale;
    At<Lanes>(s.weight, at) = nf * At<Lanes>(s.weight, at) + one;
    At<Lanes>(s.updates, at) += one;
    At<Lanes>(s.last_error, at) = e;
    At<Lanes>(s.excitation, at) = r;
    At<Lanes>(s.norm2, at) = norm2;
    At<Lanes>(s.frozen, at) = zero;
    At<Lanes>(s.outcome, at) = zero + static_cast<double>(RlsOutcome::kUpdated);
    return;
  }
  // theta, U and D of the lanes that update; the noise sums and bookkeeping of the valid ones.
#pragma GCC unroll 16
  for (std::size_t i = 0; i < kN; ++i)
    Assign(apply, At<Lanes>(s.theta[i], at) + k[i] * step, At<Lanes>(s.theta[i], at));
#pragma GCC unroll 16
  for (std::size_t j = 0; j < kN; ++j) {
    Assign(factors, divide_d ? nd[j] / (zero + lambda) : nd[j], At<Lanes>(s.d[j], at));
#pragma GCC unroll 16
    for (std::size_t i = 0; i < j; ++i) Assign(factors, nu[i][j], At<Lanes>(s.u[Upper(i, j)], at));
  }
  const Lanes nf = (zero + noise_forgetting_);
  Assign(valid, nf * At<Lanes>(s.ssr, at) + e * e / scale, At<Lanes>(s.ssr, at));
  Assign(valid, nf * At<Lanes>(s.weight, at) + one, At<Lanes>(s.weight, at));
  // Counts: + 1 where the mask is set.
  const Mask invalid = ~valid;
  CountWhere(invalid, At<Lanes>(s.rejected_invalid, at));
  CountWhere(apply, At<Lanes>(s.updates, at));
  CountWhere(frozen, At<Lanes>(s.frozen_count, at));
  Assign(valid, e, At<Lanes>(s.last_error, at));
  Assign(valid, r, At<Lanes>(s.excitation, at));
  Assign(valid, norm2, At<Lanes>(s.norm2, at));
  Lanes froze = zero;
  Assign(frozen, one, froze);
  Assign(valid, froze, At<Lanes>(s.frozen, at));
  // apply and frozen are disjoint.
  Lanes outcome = zero + static_cast<double>(RlsOutcome::kRejectedInvalid);
  Assign(frozen, zero + static_cast<double>(RlsOutcome::kFrozen), outcome);
  Assign(apply, zero + static_cast<double>(RlsOutcome::kUpdated), outcome);
  At<Lanes>(s.outcome, at) = outcome;
}

template <int N>
void RlsBank<N>::BoundLanes(Block& s, int first_lane) {
  // The box and the trace bounds, lane by lane (not configured by default).
  for (std::size_t l = 0; l < kLanes; ++l) {
    const int lane = first_lane + static_cast<int>(l);
    if (lane >= lanes_ || s.outcome[l] != static_cast<double>(RlsOutcome::kUpdated)) continue;
    LaneState& st = state_[Index(lane)];
    if (has_box_) {
      bool moved = false;
      for (std::size_t i = 0; i < kN; ++i) {
        const auto ii = static_cast<Eigen::Index>(i);
        const double v = std::clamp(s.theta[i][l], lower_(ii), upper_(ii));
        if (v != s.theta[i][l]) {
          s.theta[i][l] = v;
          moved = true;
        }
      }
      if (moved) ++st.projections;
    }
    st.bounded = false;
    if (!trace_bounds_) continue;
    double t = 0.0;  // Rls::Trace's sum, in its order
    for (std::size_t j = 0; j < kN; ++j) {
      double col = 1.0;
      for (std::size_t i = 0; i < j; ++i) col += s.u[Upper(i, j)][l] * s.u[Upper(i, j)][l];
      t += s.d[j][l] * col;
    }
    double factor = 1.0;
    if (t > options_.trace_max) {
      factor = options_.trace_max / t;
      st.bounded = true;
    } else if (t < options_.trace_min) {
      factor = options_.trace_min / t;
      st.bounded = true;
    }
    if (st.bounded) {
      for (std::size_t j = 0; j < kN; ++j) s.d[j][l] *= factor;
      ++st.trace_bounded;
    }
  }
}

// The sizes canalid uses are compiled once, in rls_bank_instances.cc (see CANALID_RLS_SIZE in
// rls.h). Not 1: every member of RlsBank<1> compiled trips GCC 12's -Warray-bounds on the empty
// strict upper triangle, in loops that never run; the one-parameter ARX bank compiles what it uses.
// `prefix` is `extern` or nothing, which cannot take the parentheses clang-tidy asks for.
// NOLINTBEGIN(bugprone-macro-parentheses)
#define CANALID_RLS_BANK_SIZES(prefix) \
  prefix template class RlsBank<2>;    \
  prefix template class RlsBank<3>;    \
  prefix template class RlsBank<4>;    \
  prefix template class RlsBank<5>;    \
  prefix template class RlsBank<6>;    \
  prefix template class RlsBank<7>;    \
  prefix template class RlsBank<8>;
// NOLINTEND(bugprone-macro-parentheses)
CANALID_RLS_BANK_SIZES(extern)

}  // namespace canalid::core
