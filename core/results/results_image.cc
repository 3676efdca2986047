#include "core/results/results_image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/registers/register_codec.h"

namespace canalid::core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

std::array<std::uint16_t, 2> F32Words(double value) {
  std::array<std::uint16_t, 2> w{};
  EncodeFloat32(static_cast<float>(value), WordOrder::kHighWordFirst, w);
  return w;
}

std::uint32_t SaturatedU32(std::int64_t value) {
  return static_cast<std::uint32_t>(
      std::clamp<std::int64_t>(value, 0, std::numeric_limits<std::uint32_t>::max()));
}

}  // namespace

ResultsImage::ResultsImage(std::vector<std::string> reaches, double start_time_s)
    : reaches_(std::move(reaches)) {
  if (static_cast<int>(reaches_.size()) > kResultsMaxReaches) {
    throw std::invalid_argument("the results map holds at most " +
                                std::to_string(kResultsMaxReaches) + " reaches, not " +
                                std::to_string(reaches_.size()));
  }
  const int n = reach_count();
  const auto& kinds = ResultsKinds();
  const int kind_count = static_cast<int>(kinds.size());
  words_.assign(static_cast<std::size_t>(ResultsImageWords(n)), 0);
  start_stamp_ = static_cast<int>(stamps_.size());
  stamps_.push_back(start_time_s);
  PutU16(kHeaderVersion, kResultsMapVersion);
  PutU16(kHeaderReachCount, static_cast<std::uint16_t>(n));
  PutU16(kHeaderFirstReach, kResultsFirstReach);
  PutU16(kHeaderReachStride, kResultsReachStride);
  PutU16(kHeaderOnlineOffset, kResultsOnlineOffset);
  PutU16(kHeaderBatchOffset, kResultsBatchOffset);
  for (int r = 0; r < n; ++r) {
    const int base = ResultsReachAddress(r);
    const std::string& name = reaches_[static_cast<std::size_t>(r)];
    for (int i = 0; i < 2 * kResultsNameWords && i < static_cast<int>(name.size()); ++i) {
      const auto byte =
          static_cast<std::uint16_t>(static_cast<unsigned char>(name[static_cast<std::size_t>(i)]));
      const int word = base + i / 2;
      words_[static_cast<std::size_t>(word)] |=
          static_cast<std::uint16_t>(i % 2 == 0 ? byte << 8 : byte);
    }
    PutU16(base + kReachCommsStatus, kResultsNoPollYet);
    PutF32(base + kReachLevel, kNan);
    PutF32(base + kReachSetpoint, kNan);
    reach_stamps_.push_back(AddStamp(base + kReachPollAge));
    AddStamp(base + kReachGoodPollAge);
    for (const ResultsKind& kind : kinds) {
      for (const bool batch : {false, true}) {
        const int slot = ResultsSlotAddress(r, kind, batch);
        AddStamp(slot + kSlotAge);
        PutF32(slot + kSlotErrorRms, kNan);
        for (std::size_t p = 0; p < kind.params.size(); ++p) {
          const int at =
              slot + kResultsSlotHeaderWords + kResultsWordsPerParam * static_cast<int>(p);
          PutF32(at, kNan);
          PutF32(at + 2, kNan);
        }
      }
    }
  }
  std::sort(ages_.begin(), ages_.end(),
            [](const Age& a, const Age& b) { return a.address < b.address; });
  const int flag_count = n * kind_count;
  online_flags_.assign(static_cast<std::size_t>(flag_count), 0);
  polls_.assign(static_cast<std::size_t>(n), 0);
  failed_polls_.assign(static_cast<std::size_t>(n), 0);
}

int ResultsImage::AddStamp(int address) {
  const int index = static_cast<int>(stamps_.size());
  stamps_.push_back(kNan);
  ages_.push_back({address, index});
  return index;
}

int ResultsImage::FindReach(std::string_view name) const {
  for (std::size_t r = 0; r < reaches_.size(); ++r) {
    if (reaches_[r] == name) return static_cast<int>(r);
  }
  return -1;
}

void ResultsImage::PutU32(int address, std::uint32_t value) {
  EncodeUint32(value, WordOrder::kHighWordFirst,
               std::span<std::uint16_t, 2>(words_.data() + address, 2));
}

void ResultsImage::PutF32(int address, double value) {
  const auto w = F32Words(value);
  words_[static_cast<std::size_t>(address)] = w[0];
  words_[static_cast<std::size_t>(address) + 1] = w[1];
}

void ResultsImage::Changed() {
  words_[kHeaderChanges] = static_cast<std::uint16_t>(words_[kHeaderChanges] + 1);
}

bool ResultsImage::SetModel(int reach, const ResultsModel& model) {
  const ResultsKind* kind = FindResultsKind(model.kind);
  if (kind == nullptr || reach < 0 || reach >= reach_count()) return false;
  const auto& kinds = ResultsKinds();
  const auto kind_index = static_cast<int>(kind - kinds.data());
  const bool batch = IsBatchEstimator(model.estimator);
  const int slot = ResultsSlotAddress(reach, *kind, batch);
  PutU16(slot + kSlotPublished, 1);
  PutU16(slot + kSlotEstimator, ResultsEstimatorCode(model.estimator));
  PutU16(slot + kSlotFlags, static_cast<std::uint16_t>(model.flags & 0xFFFF));
  PutU32(slot + kSlotSamples, SaturatedU32(model.samples_used));
  PutF32(slot + kSlotErrorRms, model.prediction_error_rms);
  const int params = static_cast<int>(kind->params.size());
  for (int p = 0; p < params; ++p) {
    const int at = slot + kResultsSlotHeaderWords + kResultsWordsPerParam * p;
    PutF32(at, kNan);
    PutF32(at + 2, kNan);
  }
  int unmapped = 0;
  for (std::size_t i = 0; i < model.names.size(); ++i) {
    const auto it = std::find(kind->params.begin(), kind->params.end(), model.names[i]);
    if (it == kind->params.end()) {
      ++unmapped;
      continue;
    }
    const int at = slot + kResultsSlotHeaderWords +
                   kResultsWordsPerParam * static_cast<int>(it - kind->params.begin());
    PutF32(at, i < model.values.size() ? model.values[i] : kNan);
    PutF32(at + 2, i < model.std_devs.size() ? model.std_devs[i] : kNan);
  }
  PutU16(slot + kSlotUnmapped, static_cast<std::uint16_t>(unmapped));
  const int first = reach_stamps_[static_cast<std::size_t>(reach)];
  const int stamp = first + 2 + 2 * kind_index + (batch ? 1 : 0);
  stamps_[static_cast<std::size_t>(stamp)] = model.time_s;
  if (!batch) {
    const int kind_count = static_cast<int>(kinds.size());
    const int reach_first = reach * kind_count;
    const auto flags =
        std::span<std::int32_t>(online_flags_)
            .subspan(static_cast<std::size_t>(reach_first), static_cast<std::size_t>(kind_count));
    flags[static_cast<std::size_t>(kind_index)] = model.flags;
    std::int32_t health = 0;
    for (const std::int32_t f : flags) health |= f;
    PutU16(ResultsReachAddress(reach) + kReachHealth, static_cast<std::uint16_t>(health & 0xFFFF));
  }
  Changed();
  return true;
}

void ResultsImage::SetPoll(int reach, const ResultsPoll& poll) {
  if (reach < 0 || reach >= reach_count()) return;
  const auto r = static_cast<std::size_t>(reach);
  const int base = ResultsReachAddress(reach);
  PutU16(base + kReachCommsStatus, poll.status);
  PutU16(base + kReachExceptionCode, poll.exception_code);
  ++polls_[r];
  if (poll.status != 0) ++failed_polls_[r];
  PutU32(base + kReachPolls, polls_[r]);
  PutU32(base + kReachFailedPolls, failed_polls_[r]);
  PutF32(base + kReachLevel, poll.level_m);
  const int first = reach_stamps_[r];
  stamps_[static_cast<std::size_t>(first)] = poll.time_s;
  if (poll.status == 0) stamps_[static_cast<std::size_t>(first) + 1] = poll.time_s;
  Changed();
}

void ResultsImage::SetExperiment(int reach, const ResultsExperiment& e) {
  if (reach < 0 || reach >= reach_count()) return;
  const int base = ResultsReachAddress(reach);
  PutU16(base + kReachExperimentState, e.state);
  PutU16(base + kReachAbortReason, e.abort_reason);
  PutF32(base + kReachProgress, e.progress);
  PutF32(base + kReachTimeLeft, e.time_left_s);
  PutF32(base + kReachSetpoint, e.setpoint);
  Changed();
}

void ResultsImage::Read(double now_s, int first, std::span<std::uint16_t> out) const {
  const auto count = static_cast<int>(out.size());
  std::copy_n(words_.begin() + first, out.size(), out.begin());
  // A two-word dynamic field at `address`, written where it overlaps [first, first + count).
  auto put = [&](int address, std::array<std::uint16_t, 2> w) {
    for (int i = 0; i < 2; ++i) {
      const int at = address + i - first;
      if (at >= 0 && at < count) out[static_cast<std::size_t>(at)] = w[static_cast<std::size_t>(i)];
    }
  };
  if (first < kHeaderUptime + 2) {
    const double uptime = std::max(0.0, now_s - stamps_[static_cast<std::size_t>(start_stamp_)]);
    std::array<std::uint16_t, 2> w{};
    EncodeUint32(static_cast<std::uint32_t>(std::min(uptime, 4294967295.0)),
                 WordOrder::kHighWordFirst, w);
    put(kHeaderUptime, w);
  }
  auto it = std::lower_bound(ages_.begin(), ages_.end(), first - 1,
                             [](const Age& a, int address) { return a.address < address; });
  for (; it != ages_.end() && it->address < first + count; ++it) {
    const double stamp = stamps_[static_cast<std::size_t>(it->stamp)];
    put(it->address, F32Words(std::isnan(stamp) ? kNan : now_s - stamp));
  }
}

}  // namespace canalid::core
