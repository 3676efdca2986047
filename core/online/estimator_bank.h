#pragma once
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace canalid::core {

/// What BankSelector compares.
enum class BankCriterion : std::uint8_t {
  /// Each candidate's exponentially weighted squared a-priori prediction error (Record), with
  /// hysteresis: noise-driven switches are damped, but the choice depends on the path (which
  /// candidate led while the estimators converged).
  kPredictionError,
  /// Each candidate's own least-squares loss (SetLoss: its residual sum of squares, weighted by
  /// its forgetting), the smallest taken on every sample, no hysteresis.  With lambda = 1 and a
  /// large P0 this is the loss a batch scan over the same rows minimises, so the bank chooses the
  /// batch fit's candidate at every sample.
  kResidual,
};

/// Options of BankSelector.
struct BankSelectorOptions {
  BankCriterion criterion = BankCriterion::kPredictionError;
  // kPredictionError only: the loss's memory and the hysteresis.
  double loss_forgetting = 0.99;  ///< gamma of the loss J_i <- gamma J_i + (1 - gamma) e_i^2
  double switch_margin = 0.1;     ///< a challenger must have J < (1 - margin) J_selected ...
  int switch_hold_samples = 20;   ///< ... on this many consecutive samples to take over
  int warmup_samples = 20;        ///< errors of the first samples are not recorded

  /// @throws std::invalid_argument naming the option out of range.
  void Validate() const;
};

/// `options` for a bank whose estimators' residual sums of squares are least-squares losses
/// (`least_squares`: e.g. IsLeastSquaresMethod of their RLS method) or not (an IV bank, a
/// constant-trace or Kalman update): kResidual applies only to the former; the latter choose by
/// the prediction error.
inline BankSelectorOptions SelectorOptionsFor(BankSelectorOptions options, bool least_squares) {
  if (!least_squares) options.criterion = BankCriterion::kPredictionError;
  return options;
}

/// Chooses one of a bank of estimators (BankCriterion).  kPredictionError: by the exponentially
/// weighted squared a-priori prediction error, with hysteresis: the selection changes only when
/// the best candidate beats the selected one by the margin on switch_hold_samples consecutive
/// samples (the first choice after the warm-up is simply the best).  kResidual: the candidate of
/// smallest loss after each sample past the warm-up (ties: the first).  Allocates only in the
/// constructor.  Pure, not thread-safe.
class BankSelector final {
 public:
  /// @throws std::invalid_argument if num_candidates < 1 or an option is out of range.
  BankSelector(int num_candidates, const BankSelectorOptions& options);

  /// kPredictionError: records candidate i's a-priori error of the current sample (non-finite
  /// errors are ignored).
  void Record(int i, double prediction_error);
  /// kResidual: candidate i's loss after the current sample (non-finite: the candidate is not
  /// chosen until its loss is finite again; while no loss is finite the choice stays as it was).
  void SetLoss(int i, double loss) { loss_[static_cast<std::size_t>(i)] = loss; }
  /// kResidual: every candidate's loss, to be written in place (as SetLoss) before Commit; one
  /// per candidate.
  std::span<double> LossSlots() { return loss_; }
  /// Closes the sample: updates the choice.  Returns the selected index (-1 during the warm-up).
  int Commit();

  int selected() const { return selected_; }
  BankCriterion criterion() const { return options_.criterion; }
  /// Candidate i's loss (infinity where it is not finite).
  double loss(int i) const {
    const double l = loss_[static_cast<std::size_t>(i)];
    return std::isfinite(l) ? l : std::numeric_limits<double>::infinity();
  }
  int num_candidates() const { return static_cast<int>(loss_.size()); }
  int switches() const { return switches_; }
  void Reset();

 private:
  /// The first candidate of smallest loss (non-finite losses never smallest; 0 when none is
  /// finite).
  int FirstSmallest() const;

  BankSelectorOptions options_;
  std::vector<double> loss_;  // as given: non-finite ones too
  int samples_ = 0;
  int selected_ = -1;
  int challenger_ = -1;
  int challenger_count_ = 0;
  int switches_ = 0;
};

}  // namespace canalid::core
