#include "core/online/online_fractional.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/online/online_gl_regressor.h"
#include "core/online/option_checks.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void Fail(const char* name, double value, const char* range) {
  ThrowOptionOutOfRange("OnlineFractionalOptions", name, value, range);
}

// The span of the tc grid in units of h: the memory, at least a decade.
double SpanSamples(int memory_samples) { return std::max(memory_samples, 10); }

// dst += w * column for the columns of a column-major block (rows x columns, one sample per
// column): the GL sums of every tc of one alpha over a run of samples.
void AddWeightedColumns(const double* block, const double* w, int columns, int rows, double* dst) {
  if (columns == 0) return;
  const Eigen::Map<const Eigen::MatrixXd> m(block, rows, columns);
  const Eigen::Map<const Eigen::VectorXd> weights(w, columns);
  Eigen::Map<Eigen::VectorXd>(dst, rows).noalias() += m * weights;
}

}  // namespace

int OnlineFractionalOptions::num_time_points() const {
  return 1 + static_cast<int>(
                 std::ceil(kTimePointsPerDecade * std::log10(SpanSamples(memory_samples))));
}

double OnlineFractionalOptions::characteristic_time_s(int i) const {
  const int n = num_time_points();
  return sample_time_s *
         std::pow(SpanSamples(memory_samples), static_cast<double>(i) / static_cast<double>(n - 1));
}

void OnlineFractionalOptions::Validate() const {
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    Fail("sample_time_s", sample_time_s, "finite, > 0");
  }
  if (alphas.empty()) Fail("alphas.size()", 0, ">= 1");
  for (double a : alphas) {
    if (!(a > 0.0 && a < 2.0)) Fail("alphas[]", a, "0 < alpha < 2");
  }
  if (memory_samples < 1 || memory_samples > 1000000) {
    Fail("memory_samples", memory_samples, "1..1000000");
  }
  const double values = static_cast<double>(alphas.size()) * memory_samples * num_time_points();
  if (values > kMaxHistoryValues) {
    Fail("memory_samples", memory_samples,
         "alphas x memory_samples x time points (10 per decade of the memory) <= 2e7");
  }
  if (delay_samples < 0) Fail("delay_samples", delay_samples, ">= 0");
  if (!(input_abs_max > 0.0)) Fail("input_abs_max", input_abs_max, "> 0");
  if (!(output_abs_max > 0.0)) Fail("output_abs_max", output_abs_max, "> 0");
  rls.Validate(2);
  selector.Validate();
}

OnlineFractionalBank::OnlineFractionalBank(const OnlineFractionalOptions& options)
    : options_((options.Validate(), options)),
      time_points_(options.num_time_points()),
      memory_(options.memory_samples),
      selector_(static_cast<int>(options.alphas.size()) * options.num_time_points(),
                SelectorOptionsFor(options.selector, IsLeastSquaresMethod(options.rls.method))),
      u_history_(options.delay_samples + 1) {
  const auto alphas = options_.alphas.size();
  const auto points = static_cast<std::size_t>(time_points_);
  const auto memory = static_cast<std::size_t>(memory_);
  reversed_.resize(alphas * memory);
  for (std::size_t a = 0; a < alphas; ++a) {
    // The GL weights, stored from w_L down to w_1.
    const OnlineGlRegressor gl(options_.alphas[a], memory_);
    for (std::size_t j = 1; j <= memory; ++j) {
      reversed_[a * memory + memory - j] = gl.weight(static_cast<int>(j));
    }
    for (int t = 0; t < time_points_; ++t) {
      c_.push_back(
          std::pow(options_.characteristic_time_s(t) / options_.sample_time_s, options_.alphas[a]));
    }
  }
  history_.assign(alphas * memory * points, 0.0);
  sums_.assign(points, 0.0);
  x_.assign(alphas * points, 0.0);
  estimators_.assign(alphas * points, Rls<2>(options_.rls));
}

bool OnlineFractionalBank::Update(double u, double y) {
  ++k_;
  ++health_.samples;
  if (FiniteWithin(u, options_.input_abs_max)) {
    u_good_ = u;
  } else {
    ++health_.bad_inputs;
  }
  u_history_.Push(u_good_);
  const double u_delayed = k_ >= options_.delay_samples ? u_history_[options_.delay_samples] : 0.0;

  // Every candidate's x(k) from its last L outputs: per alpha, the samples oldest first against
  // w_filled .. w_1, in the ring's two runs (rows head_..L-1 are older than 0..head_-1 once full).
  const int points = time_points_;
  const int alphas = static_cast<int>(options_.alphas.size());
  const int older = filled_ == memory_ ? memory_ - head_ : 0;
  const int newer = filled_ == memory_ ? head_ : filled_;
  for (int a = 0; a < alphas; ++a) {
    double* ring = history_.data() + static_cast<std::ptrdiff_t>(a) * memory_ * points;
    const double* w =
        reversed_.data() + static_cast<std::ptrdiff_t>(a) * memory_ + (memory_ - filled_);
    std::fill(sums_.begin(), sums_.end(), 0.0);
    AddWeightedColumns(ring + static_cast<std::ptrdiff_t>(head_) * points, w, older, points,
                       sums_.data());
    AddWeightedColumns(ring, w + older, newer, points, sums_.data());
    double* row = ring + static_cast<std::ptrdiff_t>(head_) * points;
    const auto first = static_cast<std::size_t>(a) * sums_.size();
    for (std::size_t t = 0; t < sums_.size(); ++t) {
      const std::size_t i = first + t;
      x_[i] = (u_delayed - c_[i] * sums_[t]) / (1.0 + c_[i]);
      row[t] = x_[i];
    }
  }
  head_ = head_ + 1 == memory_ ? 0 : head_ + 1;
  filled_ = std::min(filled_ + 1, memory_);

  const bool y_ok = FiniteWithin(y, options_.output_abs_max);
  if (!y_ok) {
    ++health_.bad_outputs;
    return false;
  }
  const bool residual = selector_.criterion() == BankCriterion::kResidual;
  for (int i = 0; i < num_candidates(); ++i) {
    Rls<2>& rls = estimators_[static_cast<std::size_t>(i)];
    const auto result = rls.Update(Eigen::Vector2d(x_[static_cast<std::size_t>(i)], 1.0), y);
    if (residual) {
      selector_.SetLoss(i, rls.residual_sum_of_squares());
    } else {
      selector_.Record(i, result.prediction_error);
    }
  }
  selector_.Commit();
  health_.switches = selector_.switches();
  return true;
}

void OnlineFractionalBank::FillCovarianceHealth(const Rls<2>& rls, FractionalSnapshot& s) const {
  Eigen::Matrix2d p;
  rls.Covariance(p);
  // Eigenvalues of the symmetric 2 x 2 P in closed form.
  const double mean = 0.5 * (p(0, 0) + p(1, 1));
  const double radius = std::hypot(0.5 * (p(0, 0) - p(1, 1)), p(0, 1));
  const double lambda_max = mean + radius;
  const double lambda_min = mean - radius;
  s.condition_number =
      lambda_min > 0.0 ? lambda_max / lambda_min : std::numeric_limits<double>::infinity();
  s.information_min = lambda_max > 0.0 ? 1.0 / lambda_max : 0.0;
  s.prediction_error = rls.last_prediction_error();
  s.innovation_std = std::sqrt(rls.innovation_variance());
  s.health = rls.health();
}

FractionalSnapshot OnlineFractionalBank::CandidateSnapshot(int index) const {
  FractionalSnapshot s;
  if (index < 0 || index >= num_candidates()) return s;
  const auto ui = static_cast<std::size_t>(index);
  const int a = index / time_points_;
  const int t = index % time_points_;
  const Rls<2>& rls = estimators_[ui];
  s.valid = rls.health().updates > 0;
  s.sample = k_;
  s.alpha = options_.alphas[static_cast<std::size_t>(a)];
  s.gain = rls.theta()(0);
  s.offset = rls.theta()(1);
  s.time_constant_s = std::pow(options_.characteristic_time_s(t), s.alpha);
  s.gain_std = rls.StandardDeviation(0);
  s.offset_std = rls.StandardDeviation(1);
  s.time_constant_std_s = kNan;
  const int last_alpha = static_cast<int>(options_.alphas.size()) - 1;
  s.at_grid_edge =
      t == 0 || t == time_points_ - 1 || (last_alpha > 0 && (a == 0 || a == last_alpha));
  FillCovarianceHealth(rls, s);
  s.loss = Loss(index);
  return s;
}

FractionalSnapshot OnlineFractionalBank::Snapshot() const {
  const int selected = selector_.selected();
  if (selected < 0) return FractionalSnapshot{};
  FractionalSnapshot s = CandidateSnapshot(selected);
  const int t = selected % time_points_;
  if (t == 0 || t == time_points_ - 1) return s;
  // The parabola through the losses at log tc - dx, log tc, log tc + dx: its vertex at p dx,
  // -1/2 <= p <= 1/2 when the middle loss is the smallest.
  const double l0 = Loss(selected - 1);
  const double l1 = Loss(selected);
  const double l2 = Loss(selected + 1);
  const double curvature = l0 - 2.0 * l1 + l2;  // J'' dx^2
  if (!(std::isfinite(curvature) && curvature > 0.0)) return s;
  const double p = std::clamp(0.5 * (l0 - l2) / curvature, -1.0, 1.0);
  const double dx = std::log(options_.characteristic_time_s(1) / options_.characteristic_time_s(0));
  const double tc = options_.characteristic_time_s(t) * std::exp(p * dx);
  s.time_constant_s = std::pow(tc, s.alpha);
  // K and the offset at the vertex: the quadratic through the three candidates' values.
  const auto at_index = static_cast<std::size_t>(selected);
  const auto& below = estimators_[at_index - 1].theta();
  const auto& at = estimators_[at_index].theta();
  const auto& above = estimators_[at_index + 1].theta();
  const Eigen::Vector2d theta =
      0.5 * p * (p - 1.0) * below + (1.0 - p * p) * at + 0.5 * p * (p + 1.0) * above;
  s.gain = theta(0);
  s.offset = theta(1);
  // The profile loss J(log tc) ~ J_min + J''/2 (log tc - log tc*)^2 gives
  // var(log tc) = 2 sigma2 / J''; T = tc^alpha, so std(T) = alpha T std(log tc).  K and the
  // offset at fixed tc have the candidate's variance; as tc varies they follow the interpolated
  // fit theta*(log tc), which adds (d theta* / d log tc)^2 var(log tc).  That needs the losses
  // to be residual sums of squares (kResidual); the prediction-error criterion's are weighted
  // means, and T's deviation is then not given.
  if (selector_.criterion() != BankCriterion::kResidual) return s;
  const double sigma2 = estimators_[at_index].innovation_variance();
  const double log_tc_variance = 2.0 * sigma2 * dx * dx / curvature;
  s.time_constant_std_s = s.alpha * s.time_constant_s * std::sqrt(log_tc_variance);
  const Eigen::Vector2d slope = ((p - 0.5) * below - 2.0 * p * at + (p + 0.5) * above) / dx;
  s.gain_std = std::sqrt(s.gain_std * s.gain_std + slope(0) * slope(0) * log_tc_variance);
  s.offset_std = std::sqrt(s.offset_std * s.offset_std + slope(1) * slope(1) * log_tc_variance);
  return s;
}

}  // namespace canalid::core
