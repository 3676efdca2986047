#pragma once
// The estimators behind MakeOnlineModel, one file each (online_*_model.cc), and what they share;
// for the files of core/online only.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/online/online_model.h"
#include "core/online/operating_point.h"

namespace canalid::core {

std::unique_ptr<OnlineModel> MakeOnlineIntegratorDelayModel(const OnlineModelOptions& options);
std::unique_ptr<OnlineModel> MakeOnlineArxModel(const OnlineModelOptions& options);
std::unique_ptr<OnlineModel> MakeOnlineFractionalModel(const OnlineModelOptions& options);
std::unique_ptr<OnlineModel> MakeOnlineLpvModel(const OnlineModelOptions& options);
std::unique_ptr<OnlineModel> MakeOnlineFracSsModel(const OnlineModelOptions& options);

/// The flags every recursive estimator's health gives: kFlagNan when `values_finite` is false or
/// trace(P) is not finite, kFlagWindup, kFlagFrozen, kFlagIllConditioned above condition_max.
int RlsHealthFlags(const RlsHealth& health, double condition, double condition_max,
                   bool values_finite);

/// Fills an OnlineModelSnapshot parameter by parameter, in the order of `names`.  No allocation.
class SnapshotWriter final {
 public:
  SnapshotWriter(OnlineModelSnapshot& out, OnlineModelKind kind, std::string_view estimator,
                 bool valid, std::int64_t samples_used, std::span<const std::string> names);
  /// The next parameter.  @pre fewer than names.size() so far.
  void Put(double value, double std_dev);
  /// The health fields; the flags RlsHealthFlags gives (none while not valid), plus `extra_flags`.
  void Finish(const RlsHealth& health, double condition, double excitation, double error_rms,
              double condition_max, int extra_flags = 0);
  bool valid() const { return out_.valid; }

 private:
  OnlineModelSnapshot& out_;
  std::size_t next_ = 0;
  bool finite_ = true;
};

/// What the process models (arx, frac-foptd, lpv, frac-ss: actuator to level) share: the operating
/// point their deviations are taken from, their parameter names (the kind's, then the operating
/// point's two), Ts and the conditioning bound.
class ProcessOnlineModel : public OnlineModel {
 protected:
  /// `names`: the kind's own parameters; "input_operating_point" and "level_operating_point_m"
  /// follow.
  ProcessOnlineModel(const OnlineModelOptions& options, std::vector<std::string> names);

  struct Deviations {
    double input;
    double output;
  };
  /// The sample's input and level as deviations from the operating point, which the first
  /// sample with both finite sets (NaN until then).
  Deviations Deviate(const OnlineSample& sample);
  SnapshotWriter Writer(OnlineModelSnapshot& out, std::string_view estimator, bool valid,
                        std::int64_t samples_used) const;
  /// Puts the two operating-point parameters (exact: standard deviation 0), the level's moved by
  /// a fitted `level_offset` (the level at rest as a deviation from the first sample's) with its
  /// standard deviation.
  void PutOperatingPoint(SnapshotWriter& writer, double level_offset = 0.0,
                         double level_offset_std = 0.0) const;
  void ResetOperatingPoint() { point_.Reset(); }

  double sample_time_s() const { return sample_time_s_; }
  double condition_max() const { return condition_max_; }

 private:
  OperatingPoint point_;
  std::vector<std::string> names_;
  double sample_time_s_;
  double condition_max_;
};

}  // namespace canalid::core
