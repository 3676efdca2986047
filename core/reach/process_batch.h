#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/linear/arx.h"
#include "core/linear/process_model_fit.h"

namespace canalid::core {

/// The process models (actuator to level) a reach identifies at the end of an experiment, beside
/// the integrator-delay model: the batch fits of `canalid identify`.
enum class ProcessBatchKind : std::uint8_t {
  kFoptd,            ///< "foptd": K e^{-tau s} / (1 + T s)  (FitFoptd)
  kFractionalFoptd,  ///< "frac-foptd": K e^{-tau s} / (1 + T s^alpha)  (FitFractionalFoptd)
  kSoptd,            ///< "soptd": K e^{-tau s} / ((1 + T1 s)(1 + T2 s))  (FitSoptd)
  kArx,              ///< "arx": A(q) y = B(q) q^-nk u, nk scanned (FitArxOverDelays)
  /// "frac-ss": the commensurate fractional state space, alpha = 1/q, nk scanned
  /// (FitCommensurateScanDelay)
  kFracSs,
};
inline constexpr std::array kProcessBatchKinds{
    ProcessBatchKind::kFoptd, ProcessBatchKind::kFractionalFoptd, ProcessBatchKind::kSoptd,
    ProcessBatchKind::kArx, ProcessBatchKind::kFracSs};
/// The kind's name in configurations and model JSON.
std::string_view ProcessBatchKindName(ProcessBatchKind kind);

/// What a process fit may use: one struct for the daemon's end-of-experiment fits (from the
/// reach's keys) and `canalid identify --model foptd|soptd|frac-foptd|frac-ss` (from its flags).
struct ProcessBatchOptions {
  /// >= 0: the longest delay kept (rounded to whole samples where the fit scans samples; 0 keeps
  /// only delay 0, as a reach with max_delay_s = 0 asks); < 0: each fit's default (foptd, soptd
  /// and arx a third of the record, frac-foptd half of it, frac-ss min(record / 10, 100 samples))
  double max_delay_s = -1.0;
  int min_delay_samples = 1;  ///< arx: the shortest delay tried (at least 1 sample)
  int arx_na = 2;             ///< arx: output lags (the reach's arx_na)
  int arx_nb = 2;             ///< arx: input lags (the reach's arx_nb)
  int frac_ss_q = 2;          ///< frac-ss: alpha = 1/q (the reach's frac_ss_q)
  /// frac-ss: the GL memory of the fit's simulations (samples; 0: the whole record, O(N^2) per
  /// simulation)
  int frac_ss_memory_samples = 200;
  double fixed_alpha = 0.0;  ///< frac-foptd: > 0 holds alpha there and fits the rest
};

/// One end-of-experiment fit: the kind's result, or why there is none.
struct ProcessBatchResult {
  ProcessBatchKind kind = ProcessBatchKind::kFoptd;
  std::optional<FoptdFit> foptd;  ///< kFoptd
  std::optional<SoptdFit> soptd;  ///< kSoptd
  std::optional<ArxModel> arx;    ///< kArx: of the deviations from the record's first sample
  double input_offset = 0.0;      ///< kArx: the record's first input (the rest point)
  double output_offset = 0.0;     ///< kArx: the record's first level
  std::optional<FractionalFoptdFitResult> fractional;  ///< kFractionalFoptd
  std::optional<CommensurateFitResult> commensurate;   ///< kFracSs (its own rest point)
  int memory_samples = 0;                              ///< kFracSs: the GL memory it used
  OustaloupOptions band;  ///< kFractionalFoptd: the band the fit simulated with
  /// Empty when the model is the reach's: fitted, finite, T > 0, delay inside [0, max_delay_s].
  std::string problem;

  bool ok() const { return problem.empty(); }
  /// A model was fitted (it may still have a problem with its bounds).
  bool fitted() const {
    return foptd.has_value() || soptd.has_value() || arx.has_value() || fractional.has_value() ||
           commensurate.has_value();
  }
};

/// Fits `kind` to the record of input u (the actuator) and level y sampled every Ts (the first
/// sample the rest point), with delays up to options.max_delay_s.  Never throws for bad data: the
/// fit's error becomes `problem`.
ProcessBatchResult FitProcessBatch(ProcessBatchKind kind,
                                   const Eigen::Ref<const Eigen::VectorXd>& u,
                                   const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                                   const ProcessBatchOptions& options);

}  // namespace canalid::core
