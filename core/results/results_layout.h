#pragma once
// Where canalidd's results sit in the read-only register image a SCADA polls over Modbus
// (docs/results-register-map.md).  Every address follows from the tables of this file: the map
// header, the reach block's fields, a model slot's header, and the model kinds with their
// parameters.  Addresses are Modbus PDU addresses (0-based), the same for holding registers
// (function 3) and input registers (function 4).  32-bit values are high word first (ABCD).
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace canalid::core {

inline constexpr int kResultsMapVersion = 1;
inline constexpr int kResultsFirstReach = 1000;   ///< address of reach 0's block
inline constexpr int kResultsReachStride = 2000;  ///< words between reach blocks
inline constexpr int kResultsMaxReaches = 32;     ///< so that every address fits 16 bits
inline constexpr int kResultsOnlineOffset = 100;  ///< the online slots, within a reach block
inline constexpr int kResultsBatchOffset = 1000;  ///< the batch (and persisted) slots
inline constexpr int kResultsNameWords = 8;       ///< a reach name: 16 ASCII bytes, NUL padded
inline constexpr int kResultsSlotHeaderWords = 10;
inline constexpr int kResultsWordsPerParam = 4;  ///< value f32, then its standard deviation f32

/// How a field is encoded.  f32 and u32 take two registers, high word first.
enum class ResultsType : std::uint8_t { kU16, kU32, kF32, kAscii };

/// One field of a block: its offset in the block, its type, its name and meaning (the doc's).
/// `dynamic`: computed when a request is answered (an age), not stored.
struct ResultsField {
  int offset;
  ResultsType type;
  std::string_view name;
  std::string_view meaning;
  bool dynamic = false;
};

/// The map header, at address 0.
enum ResultsHeader : int {
  kHeaderVersion = 0,
  kHeaderReachCount = 1,
  kHeaderFirstReach = 2,
  kHeaderReachStride = 3,
  kHeaderOnlineOffset = 4,
  kHeaderBatchOffset = 5,
  kHeaderUptime = 6,   ///< u32, dynamic
  kHeaderChanges = 8,  ///< u16 counter of image updates, wraps
  kHeaderWords = 10,
};

/// A reach block's status fields (at the reach's base address).
enum ResultsReachField : int {
  kReachName = 0,
  kReachCommsStatus = 8,
  kReachExceptionCode = 9,
  kReachPollAge = 10,      ///< f32, dynamic
  kReachGoodPollAge = 12,  ///< f32, dynamic
  kReachPolls = 14,
  kReachFailedPolls = 16,
  kReachLevel = 18,
  kReachExperimentState = 20,
  kReachAbortReason = 21,
  kReachProgress = 22,
  kReachTimeLeft = 24,
  kReachSetpoint = 26,
  kReachHealth = 28,
  kReachStatusWords = 29,
};

/// A model slot's header fields; its parameters follow, kResultsWordsPerParam words each.
enum ResultsSlotField : int {
  kSlotPublished = 0,
  kSlotEstimator = 1,
  kSlotFlags = 2,
  kSlotUnmapped = 3,
  kSlotAge = 4,  ///< f32, dynamic
  kSlotSamples = 6,
  kSlotErrorRms = 8,
};

/// The comms-status word's value before the first poll.
inline constexpr std::uint16_t kResultsNoPollYet = 0xFFFF;

std::span<const ResultsField> ResultsHeaderFields();
std::span<const ResultsField> ResultsReachFields();
std::span<const ResultsField> ResultsSlotFields();

/// One model kind's slot: its parameters in slot order, and the slot's offset from the start of
/// the online (or batch) slots.
struct ResultsKind {
  std::string name;  ///< as model_snapshot_t.model_kind: "id", "idz", "arx", ...
  std::vector<std::string> params;
  int offset = 0;
  int words() const {
    return kResultsSlotHeaderWords + kResultsWordsPerParam * static_cast<int>(params.size());
  }
};

/// Every kind, in slot order (the table the map is generated from).
const std::vector<ResultsKind>& ResultsKinds();
/// The kind named `name`; nullptr when it has no slot.
const ResultsKind* FindResultsKind(std::string_view name);

/// The estimator codes of a slot's estimator word (model_snapshot_t.estimator).
std::uint16_t ResultsEstimatorCode(std::string_view estimator);
/// True for the estimators whose model goes in the batch slot ("batch", "persisted").
bool IsBatchEstimator(std::string_view estimator);
/// The estimator names by code, for the doc (index = code; "" for 0, any other name).
std::span<const std::string_view> ResultsEstimatorNames();

/// Address of reach `reach`'s block.
inline int ResultsReachAddress(int reach) {
  return kResultsFirstReach + kResultsReachStride * reach;
}
/// Address of the slot of `kind` in reach `reach`'s online or batch slots.
inline int ResultsSlotAddress(int reach, const ResultsKind& kind, bool batch) {
  return ResultsReachAddress(reach) + (batch ? kResultsBatchOffset : kResultsOnlineOffset) +
         kind.offset;
}
/// Words of an image with `reaches` reaches.
inline int ResultsImageWords(int reaches) {
  return reaches == 0 ? kHeaderWords : ResultsReachAddress(reaches - 1) + kResultsReachStride;
}

/// The map of `reaches` as Markdown tables, one row per field (the reach and model-slot tables
/// list every address of the first reach; the others follow by the stride).
std::string ResultsMapMarkdown(std::span<const std::string> reaches);

}  // namespace canalid::core
