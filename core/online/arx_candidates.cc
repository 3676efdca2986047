#include "core/online/arx_candidates.h"

#include <limits>
#include <utility>
#include <vector>

#include "core/online/rls_bank.h"

namespace canalid::core {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Row c of `rows` into phi(0..n-1) (any indexable target); NaN where it reads a bad input.
template <class Set>
void FillRow(const ArxRows& rows, int c, Set set) {
  for (int i = 0; i < rows.na; ++i) set(i, rows.minus_y_lags[i]);
  const int nk = rows.min_delay + c;
  bool good = true;
  for (int j = 0; j < rows.nb; ++j) {
    set(rows.na + j, (*rows.u)[nk + j]);
    good = good && (*rows.u_bad)[nk + j] == 0;
  }
  if (!good) {
    for (int i = 0; i < rows.na + rows.nb; ++i) set(i, kNaN);
  }
}

void Report(BankSelector& selector, int c, double loss, double prediction_error) {
  if (selector.criterion() == BankCriterion::kResidual) {
    selector.SetLoss(c, loss);
  } else {
    selector.Record(c, prediction_error);
  }
}

template <class Estimator>
void ReadState(const Estimator& rls, int n, ArxCandidateState& out) {
  out.theta = rls.theta().head(n);
  out.std_dev.resize(n);
  for (int i = 0; i < n; ++i) out.std_dev(i) = rls.StandardDeviation(i);
  out.innovation_variance = rls.innovation_variance();
  out.last_prediction_error = rls.last_prediction_error();
  out.health = rls.health();
}

// n = N parameters: the lanes of one RlsBank<N>.
template <int N>
class LaneCandidates final : public ArxCandidates {
 public:
  LaneCandidates(const RlsOptions& options, int count) : bank_(options, count) {}

  void Update(const ArxRows& rows, double y, BankSelector& selector) override {
    auto& phi = bank_.regressors();
    for (int c = 0; c < bank_.lanes(); ++c) {
      FillRow(rows, c, [&](int i, double v) { phi(i, c) = v; });
    }
    bank_.Update(y);
    for (int c = 0; c < bank_.lanes(); ++c) {
      Report(selector, c, bank_.residual_sum_of_squares(c), bank_.result(c).prediction_error);
    }
  }

  void State(int c, ArxCandidateState& out) const override { ReadState(bank_.Lane(c), N, out); }
  bool lanes() const override { return bank_.structure_of_arrays(); }

 private:
  RlsBank<N> bank_;
};

// More parameters than any RlsBank instantiated here: one Rls<Dynamic> per candidate.
class DynamicCandidates final : public ArxCandidates {
 public:
  DynamicCandidates(const RlsOptions& options, int num_params, int count)
      : phi_(Eigen::VectorXd::Zero(num_params)) {
    estimators_.reserve(static_cast<std::size_t>(count));
    for (int c = 0; c < count; ++c) estimators_.emplace_back(options, num_params);
  }

  void Update(const ArxRows& rows, double y, BankSelector& selector) override {
    for (std::size_t c = 0; c < estimators_.size(); ++c) {
      const int ci = static_cast<int>(c);
      FillRow(rows, ci, [&](int i, double v) { phi_(i) = v; });
      const auto result = estimators_[c].Update(phi_, y);
      Report(selector, ci, estimators_[c].residual_sum_of_squares(), result.prediction_error);
    }
  }

  void State(int c, ArxCandidateState& out) const override {
    ReadState(estimators_[static_cast<std::size_t>(c)], static_cast<int>(phi_.size()), out);
  }
  bool lanes() const override { return false; }

 private:
  std::vector<Rls<Eigen::Dynamic>> estimators_;
  Eigen::VectorXd phi_;
};

template <int N>
std::unique_ptr<ArxCandidates> MakeLanes(const RlsOptions& options, int num_params, int count) {
  if constexpr (N > ArxCandidates::kMaxArxLaneParams) {
    return std::make_unique<DynamicCandidates>(options, num_params, count);
  } else {
    if (num_params == N) return std::make_unique<LaneCandidates<N>>(options, count);
    return MakeLanes<N + 1>(options, num_params, count);
  }
}

}  // namespace

std::unique_ptr<ArxCandidates> ArxCandidates::Make(const RlsOptions& options, int num_params,
                                                   int count) {
  options.Validate(num_params);
  return MakeLanes<1>(options, num_params, count);
}

}  // namespace canalid::core
