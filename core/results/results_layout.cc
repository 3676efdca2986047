#include "core/results/results_layout.h"

#include <array>
#include <sstream>

namespace canalid::core {
namespace {

constexpr std::array<ResultsField, 8> kHeader{{
    {kHeaderVersion, ResultsType::kU16, "map_version", "layout version of this map (1)"},
    {kHeaderReachCount, ResultsType::kU16, "reach_count", "reaches in the map"},
    {kHeaderFirstReach, ResultsType::kU16, "first_reach_address", "address of reach 0's block"},
    {kHeaderReachStride, ResultsType::kU16, "reach_stride",
     "words from one reach block to the next"},
    {kHeaderOnlineOffset, ResultsType::kU16, "online_offset",
     "offset of the online model slots in a reach block"},
    {kHeaderBatchOffset, ResultsType::kU16, "batch_offset",
     "offset of the batch model slots in a reach block"},
    {kHeaderUptime, ResultsType::kU32, "uptime_s", "seconds since canalidd started (or reloaded)",
     true},
    {kHeaderChanges, ResultsType::kU16, "update_counter",
     "incremented on every update of the image (wraps at 65536): a SCADA watchdog"},
}};

constexpr std::array<ResultsField, 14> kReach{{
    {kReachName, ResultsType::kAscii, "reach_name",
     "the reach's name, 16 ASCII bytes (2 per register, high byte first), NUL padded, truncated"},
    {kReachCommsStatus, ResultsType::kU16, "comms_status",
     "the last poll of the reach's PLC: 0 ok, 1 timeout, 2 exception, 3 disconnected, 4 bad "
     "data, 5 configuration; 65535 before the first poll"},
    {kReachExceptionCode, ResultsType::kU16, "exception_code",
     "Modbus exception code of the last poll (0 unless comms_status is 2)"},
    {kReachPollAge, ResultsType::kF32, "poll_age_s", "seconds since the last poll (NaN: none)",
     true},
    {kReachGoodPollAge, ResultsType::kF32, "good_poll_age_s",
     "seconds since the last poll with comms_status 0 (NaN: none)", true},
    {kReachPolls, ResultsType::kU32, "polls", "polls of the reach's PLC since start"},
    {kReachFailedPolls, ResultsType::kU32, "failed_polls", "polls with comms_status other than 0"},
    {kReachLevel, ResultsType::kF32, "level_m",
     "the reach's last level sample (NaN when it was not valid)"},
    {kReachExperimentState, ResultsType::kU16, "experiment_state",
     "0 idle, 1 armed, 2 settling, 3 exciting, 4 recovering, 5 done, 6 aborted "
     "(experiment_state_t.STATE_*)"},
    {kReachAbortReason, ResultsType::kU16, "abort_reason",
     "why the last experiment aborted: 0 none, 1 level out of band, 2 level sensor invalid, 3 PLC "
     "link lost, 4 setpoint write failed, 5 stopped by operator, 6 identification failed, 7 "
     "experiment guard not persisted, 8 sample gap, 9 stopped with its joint experiment"},
    {kReachProgress, ResultsType::kF32, "experiment_progress",
     "fraction of the experiment's settle and excitation samples done, 0 to 1"},
    {kReachTimeLeft, ResultsType::kF32, "experiment_time_left_s",
     "wall-clock seconds of settling and excitation left at the poll period (0 when no "
     "experiment runs)"},
    {kReachSetpoint, ResultsType::kF32, "actuator_setpoint",
     "the last setpoint the reach's experiment asked for, the actuator's unit (NaN: none)"},
    {kReachHealth, ResultsType::kU16, "health_flags",
     "OR of the flags of the reach's latest online models (model_snapshot_t.FLAG_*)"},
}};

constexpr std::array<ResultsField, 7> kSlot{{
    {kSlotPublished, ResultsType::kU16, "published",
     "1 once a model of this kind and estimator was published, else 0"},
    {kSlotEstimator, ResultsType::kU16, "estimator",
     "1 rls-bank, 2 rls, 3 rls-bank-reset, 4 batch, 5 persisted, 0 other"},
    {kSlotFlags, ResultsType::kU16, "flags",
     "model_snapshot_t.FLAG_*: 1 NaN, 2 windup, 4 low excitation, 8 ill-conditioned, 16 frozen, "
     "32 out of bounds"},
    {kSlotUnmapped, ResultsType::kU16, "unmapped_params",
     "parameters of the model that have no place in this slot (0 for every model canalidd "
     "publishes today)"},
    {kSlotAge, ResultsType::kF32, "age_s",
     "seconds from the model's last sample to the request (NaN: none)", true},
    {kSlotSamples, ResultsType::kU32, "samples_used", "samples the estimate has seen"},
    {kSlotErrorRms, ResultsType::kF32, "prediction_error_rms",
     "RMS one-step prediction error, output unit"},
}};

constexpr std::array<std::string_view, 6> kEstimators{"",      "rls-bank", "rls", "rls-bank-reset",
                                                      "batch", "persisted"};

std::vector<std::string> Numbered(std::string_view prefix, int count,
                                  std::string_view suffix = "") {
  std::vector<std::string> names;
  for (int i = 1; i <= count; ++i) {
    names.push_back(std::string(prefix) + std::to_string(i) + std::string(suffix));
  }
  return names;
}

std::vector<ResultsKind> MakeKinds() {
  const std::vector<std::string> integrator_delay{"delay_s",
                                                  "area_m2",
                                                  "b",
                                                  "p21_s_per_m2",
                                                  "p22_s_per_m2",
                                                  "offset_m",
                                                  "drift_m_per_sample",
                                                  "fit_percent"};
  const std::vector<std::string> operating_point{"input_operating_point",
                                                 "level_operating_point_m"};
  auto join = [](std::initializer_list<std::vector<std::string>> parts) {
    std::vector<std::string> all;
    for (const auto& part : parts) all.insert(all.end(), part.begin(), part.end());
    return all;
  };
  // lpv's coefficients a<j>_<m>, b<j>_<m> (of s^m): na <= 15 and nb <= 16 (na + nb <= 16).
  std::vector<std::string> lpv{"delay_s"};
  for (const char* coefficient : {"a", "b"}) {
    for (int j = 1; j <= (coefficient[0] == 'a' ? 15 : 16); ++j) {
      for (int m = 0; m < 3; ++m) {
        lpv.push_back(coefficient + std::to_string(j) + "_" + std::to_string(m));
      }
    }
  }
  std::vector<ResultsKind> kinds{
      {"id", integrator_delay},
      {"idz", integrator_delay},
      // arx: na <= 15, nb <= 16; frac-ss: order 2 q <= 8.
      {"arx", join({{"delay_s"}, Numbered("a", 16), Numbered("b", 16), operating_point})},
      {"foptd", join({{"gain", "time_constant_s", "delay_s", "offset_m"}, operating_point})},
      {"soptd", join({{"gain", "time_constant_1_s", "time_constant_2_s", "delay_s", "offset_m"},
                      operating_point})},
      {"frac-foptd",
       join({{"gain", "time_constant_s", "alpha", "delay_s", "offset_m"}, operating_point})},
      {"frac-ss",
       join({{"delay_s", "alpha"}, Numbered("a", 8), Numbered("c", 7), operating_point})},
      {"lpv", join({lpv, operating_point})},
  };
  int offset = 0;
  for (ResultsKind& kind : kinds) {
    kind.offset = offset;
    offset += kind.words();
  }
  return kinds;
}

const char* TypeName(ResultsType type) {
  switch (type) {
    case ResultsType::kU16:
      return "u16";
    case ResultsType::kU32:
      return "u32";
    case ResultsType::kF32:
      return "f32";
    case ResultsType::kAscii:
      return "ascii[16]";
  }
  return "?";
}

void Rows(std::ostringstream& out, int base, std::span<const ResultsField> fields) {
  for (const ResultsField& f : fields) {
    out << "| " << base + f.offset << " | +" << f.offset << " | `" << f.name << "` | "
        << TypeName(f.type) << " | " << f.meaning << (f.dynamic ? " (computed per request)" : "")
        << " |\n";
  }
}

}  // namespace

std::span<const ResultsField> ResultsHeaderFields() { return kHeader; }
std::span<const ResultsField> ResultsReachFields() { return kReach; }
std::span<const ResultsField> ResultsSlotFields() { return kSlot; }
std::span<const std::string_view> ResultsEstimatorNames() { return kEstimators; }

const std::vector<ResultsKind>& ResultsKinds() {
  static const std::vector<ResultsKind> kKinds = MakeKinds();
  return kKinds;
}

const ResultsKind* FindResultsKind(std::string_view name) {
  for (const ResultsKind& kind : ResultsKinds()) {
    if (kind.name == name) return &kind;
  }
  return nullptr;
}

std::uint16_t ResultsEstimatorCode(std::string_view estimator) {
  for (std::size_t i = 1; i < kEstimators.size(); ++i) {
    if (kEstimators[i] == estimator) return static_cast<std::uint16_t>(i);
  }
  return 0;
}

bool IsBatchEstimator(std::string_view estimator) {
  return estimator == "batch" || estimator == "persisted";
}

std::string ResultsMapMarkdown(std::span<const std::string> reaches) {
  std::ostringstream out;
  out << "### Header\n\n| address | offset | field | type | meaning |\n|---|---|---|---|---|\n";
  Rows(out, 0, kHeader);
  out << "\n### Reach blocks\n\n| reach | name | block address |\n|---|---|---|\n";
  for (std::size_t r = 0; r < reaches.size(); ++r) {
    out << "| " << r << " | `" << reaches[r] << "` | " << ResultsReachAddress(static_cast<int>(r))
        << " |\n";
  }
  const int base = ResultsReachAddress(0);
  out << "\n### Reach status (addresses of reach 0; add the block address - " << base
      << " for another)\n\n| address | offset | field | type | meaning |\n|---|---|---|---|---|\n";
  Rows(out, base, kReach);
  out << "\n### Model slots (addresses of reach 0)\n\nEach slot: the header below, then its "
         "parameters, 4 words each (the value f32, then its 1-sigma standard deviation f32; "
         "NaN when not known or not part of the model).\n\n"
         "| slot header offset | field | type | meaning |\n|---|---|---|---|\n";
  for (const ResultsField& f : kSlot) {
    out << "| +" << f.offset << " | `" << f.name << "` | " << TypeName(f.type) << " | " << f.meaning
        << (f.dynamic ? " (computed per request)" : "") << " |\n";
  }
  out << "\n| kind | online slot | batch slot | words | parameters (value at slot + 10 + 4 i, "
         "standard deviation at + 2) |\n|---|---|---|---|---|\n";
  for (const ResultsKind& kind : ResultsKinds()) {
    out << "| `" << kind.name << "` | " << ResultsSlotAddress(0, kind, false) << " | "
        << ResultsSlotAddress(0, kind, true) << " | " << kind.words() << " |";
    for (std::size_t i = 0; i < kind.params.size(); ++i) {
      out << (i == 0 ? " " : ", ") << i << " `" << kind.params[i] << "`";
    }
    out << " |\n";
  }
  return out.str();
}

}  // namespace canalid::core
