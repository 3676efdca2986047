#pragma once
// The register image of the results map (results_layout.h): what the daemon last published, as
// 16-bit words, with the ages computed when a request is answered.  Pure; not thread-safe (its
// owner locks); no allocation after construction.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/results/results_layout.h"

namespace canalid::core {

/// One published model (the fields of model_snapshot_t the map shows).
struct ResultsModel {
  std::string_view kind;       ///< "id", "idz", ...; a kind with no slot is ignored
  std::string_view estimator;  ///< "batch" and "persisted" fill the batch slot, others the online
  double time_s = 0.0;         ///< time of the model's last sample (s since the epoch)
  std::int64_t samples_used = 0;
  std::span<const std::string> names;
  std::span<const double> values;    ///< names.size() values
  std::span<const double> std_devs;  ///< names.size() standard deviations
  std::int32_t flags = 0;
  double prediction_error_rms = 0.0;
};

/// One poll of a reach's PLC.
struct ResultsPoll {
  double time_s = 0.0;       ///< s since the epoch
  std::uint16_t status = 0;  ///< sample_t.status (0 ok)
  std::uint16_t exception_code = 0;
  double level_m = 0.0;  ///< NaN when the level was not valid
};

/// The state of a reach's experiment after a sample.
struct ResultsExperiment {
  std::uint16_t state = 0;         ///< experiment_state_t.STATE_*
  std::uint16_t abort_reason = 0;  ///< core::AbortReason's value
  double progress = 0.0;           ///< 0..1
  double time_left_s = 0.0;
  double setpoint = 0.0;  ///< NaN when none
};

class ResultsImage final {
 public:
  /// @throws std::invalid_argument with more than kResultsMaxReaches reaches.
  explicit ResultsImage(std::vector<std::string> reaches, double start_time_s);

  int reach_count() const { return static_cast<int>(reaches_.size()); }
  /// Index of the reach named `name`; -1 when absent.
  int FindReach(std::string_view name) const;
  int size() const { return static_cast<int>(words_.size()); }

  /// Returns false (nothing changed) when the kind has no slot or `reach` is out of range.
  bool SetModel(int reach, const ResultsModel& model);
  void SetPoll(int reach, const ResultsPoll& poll);
  void SetExperiment(int reach, const ResultsExperiment& experiment);

  /// Words [first, first + out.size()) as a request at `now_s` reads them (ages computed).
  /// @pre the range is inside the image.
  void Read(double now_s, int first, std::span<std::uint16_t> out) const;

 private:
  struct Age {
    int address;
    int stamp;  ///< index into stamps_
  };
  int AddStamp(int address);
  void PutU16(int address, std::uint16_t value) {
    words_[static_cast<std::size_t>(address)] = value;
  }
  void PutU32(int address, std::uint32_t value);
  void PutF32(int address, double value);
  void Changed();

  std::vector<std::string> reaches_;
  std::vector<std::uint16_t> words_;
  std::vector<double> stamps_;  ///< NaN: never
  std::vector<Age> ages_;       ///< sorted by address
  int start_stamp_ = 0;
  /// Per reach: its first stamp (poll, good poll, then each kind's online and batch slot).
  std::vector<int> reach_stamps_;
  /// Per reach and kind: the flags of the latest online model (for the reach's health word).
  std::vector<std::int32_t> online_flags_;
  std::vector<std::uint32_t> polls_, failed_polls_;
};

}  // namespace canalid::core
