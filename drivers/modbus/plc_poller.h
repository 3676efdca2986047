#pragma once
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/experiment/setpoint_limiter.h"
#include "drivers/modbus/channel_scaling.h"
#include "drivers/modbus/plc_port.h"
#include "drivers/modbus/read_plan.h"
#include "drivers/modbus/reconnect_backoff.h"
#include "drivers/modbus/spsc_ring.h"

namespace canalid::drivers {

/// One polled channel of a PLC.
struct PollChannel {
  std::string name;  ///< e.g. "pool2.level_m"
  RegisterKind kind = RegisterKind::kHolding;
  int address = 0;  ///< 0-based register address of the first word
  drivers::ChannelScaling scaling;
  bool writable = false;        ///< setpoint writes allowed (holding registers only)
  core::SetpointLimits limits;  ///< clamp and rate limit of writes (used when writable)
};

struct PollerConfig {
  std::string plc_name;               ///< for logs and health
  double period_s = 1.0;              ///< poll period, > the port's response timeout
  int max_gap_registers = 8;          ///< unused registers a read may span to save a request
  double backoff_initial_s = 0.5;     ///< first reconnect delay
  double backoff_max_s = 30.0;        ///< reconnect delay bound
  int timeouts_before_reconnect = 3;  ///< consecutive timed-out reads that drop the link
  int sample_queue_capacity = 64;     ///< polls buffered for the consumer
  int write_queue_capacity = 16;      ///< pending write requests (and buffered results)
  std::vector<PollChannel> channels;
};

/// @throws std::invalid_argument naming the key: empty channel list, period_s <= response
///   timeout, bad backoff, capacities < 1, a writable input register, bad scaling or limits.
void ValidatePollerConfig(const PollerConfig& config, double response_timeout_s);

/// Quality of one channel in one poll.
enum class SampleQuality : uint8_t { kValid, kReadFailed, kOutOfRange, kNotFinite };

/// One complete poll. Vectors have one entry per channel (config order) and are sized once.
struct PollSample {
  int64_t sequence = 0;        ///< 0, 1, 2 ... per poll attempt (gaps mean dropped samples)
  double time_s = 0.0;         ///< wall clock at the start of the poll, s since the Unix epoch
  double round_trip_s = 0.0;   ///< time spent in the block reads of this poll
  PlcStatus status;            ///< first failure among the block reads, or ok
  std::vector<double> values;  ///< engineering values (valid ones only)
  std::vector<SampleQuality> quality;        ///< per channel
  std::vector<std::array<uint16_t, 2>> raw;  ///< register image (second word 0 for 16-bit)
  bool valid(std::size_t i) const { return quality[i] == SampleQuality::kValid; }
};

/// Accepted or refused at the queue (before any I/O).
enum class WriteQueueStatus { kQueued, kUnknownChannel, kNotWritable, kQueueFull };
struct WriteTicket {
  WriteQueueStatus status = WriteQueueStatus::kQueued;
  uint64_t id = 0;  ///< matches WriteResult::id when queued
};

enum class WriteOutcome {
  kWritten,       ///< `written` is in the PLC (possibly clamped or rate-limited)
  kNoReference,   ///< the channel has not been read validly yet, so no rate limit can apply
  kNotFinite,     ///< requested value is NaN or infinite
  kEncodeFailed,  ///< the limited value does not fit the register type (see encode_error)
  kPlcFailed,     ///< the request failed (see plc)
};

struct WriteResult {
  uint64_t id = 0;
  int channel = 0;
  double requested = 0.0;
  double written = 0.0;
  bool clamped = false;
  bool rate_limited = false;
  WriteOutcome outcome = WriteOutcome::kWritten;
  drivers::ScalingError encode_error = drivers::ScalingError::kNone;
  PlcStatus plc;
  double time_s = 0.0;  ///< wall clock when executed
};

/// Snapshot of the poller's counters (read from any thread).
struct PollerCounters {
  int64_t polls = 0;
  int64_t block_reads_ok = 0;
  std::array<int64_t, kPlcErrorKindCount> read_errors{};  ///< by PlcErrorKind
  /// Replies (to reads and writes) that did not match their request, by ReplyFault ([0] unused).
  std::array<int64_t, kReplyFaultCount> reply_faults{};
  int64_t connect_failures = 0;
  int64_t reconnects = 0;  ///< successful connects after the first
  int64_t samples_dropped = 0;
  int64_t overruns = 0;  ///< polls that ended after the next period had begun
  int64_t writes_ok = 0;
  int64_t writes_failed = 0;
  int64_t write_results_dropped = 0;
  int64_t notify_failures = 0;  ///< exceptions thrown by the notify callback
  double last_round_trip_s = 0.0;
  double current_backoff_s = 0.0;  ///< delay before the pending reconnect attempt
  bool connected = false;
};

/// Polls one PLC on its own thread. The PlcPort (and so its libmodbus context) is used only on
/// that thread. The read plan is computed once in the constructor.
///
/// Loop: connect (on failure wait ReconnectBackoff delays: initial, 2x, 4x ... up to the bound);
/// read every block of the plan; decode each channel with drivers::DecodeChannel; hand the poll
/// over; execute queued writes; wait for the next period (writes queued meanwhile run at once). A
/// kDisconnected read, or timeouts_before_reconnect consecutive timeouts, drops the link.
///
/// Handoff to the consumer (the daemon's Asio thread): polls go into a lock-free SPSC ring of
/// preallocated PollSample slots and write results into a second one; after each push, link state
/// change or write result the poller calls `notify` on the poller thread. `notify` must be cheap
/// and thread-safe (e.g. asio::post a drain to the io_context, or write an eventfd); the consumer
/// then calls DrainSamples / DrainWriteResults on its own thread. When the ring is full the poll
/// is dropped and counted (samples_dropped), never blocking the poller. Nothing is allocated per
/// poll after construction.
///
/// Writes: RequestWrite may be called from any thread; the request (a fixed-size mutex-protected
/// queue) runs on the poller thread between polls, only for writable channels, through a
/// core::SetpointLimiter whose reference is the first valid reading of the channel after each
/// (re)connect and then the last written value.
class PlcPoller final {
 public:
  /// @throws std::invalid_argument on a bad config (ValidatePollerConfig, PlanReads).
  PlcPoller(PollerConfig config, std::unique_ptr<PlcPort> port, std::function<void()> notify);
  ~PlcPoller();  ///< Stop()s
  PlcPoller(const PlcPoller&) = delete;
  PlcPoller& operator=(const PlcPoller&) = delete;

  void Start();
  /// Asks the thread to finish (interrupting a wait, not a blocking Modbus call) and joins it.
  void Stop();

  /// Consumer: calls f(const PollSample&) for each buffered poll, oldest first; returns the count.
  template <class F>
  int DrainSamples(F&& f) {
    int n = 0;
    for (const PollSample* s = samples_.Front(); s != nullptr; s = samples_.Front(), ++n) {
      f(*s);
      samples_.Pop();
    }
    return n;
  }
  /// Consumer: calls f(const WriteResult&) for each finished write; returns the count.
  template <class F>
  int DrainWriteResults(F&& f) {
    int n = 0;
    for (const WriteResult* r = results_.Front(); r != nullptr; r = results_.Front(), ++n) {
      f(*r);
      results_.Pop();
    }
    return n;
  }

  /// Any thread: queue a setpoint write of `value` (engineering unit) to channel `channel`.
  WriteTicket RequestWrite(int channel, double value);

  PollerCounters counters() const;
  const ReadPlan& plan() const { return plan_; }
  const PollerConfig& config() const { return config_; }

 private:
  struct WriteRequest {
    uint64_t id = 0;
    int channel = 0;
    double value = 0.0;
  };
  struct AtomicCounters {
    std::atomic<int64_t> polls{0}, block_reads_ok{0}, connect_failures{0}, reconnects{0},
        samples_dropped{0}, overruns{0}, writes_ok{0}, writes_failed{0}, write_results_dropped{0},
        notify_failures{0};
    std::array<std::atomic<int64_t>, kPlcErrorKindCount> read_errors{};
    std::array<std::atomic<int64_t>, kReplyFaultCount> reply_faults{};
    std::atomic<double> last_round_trip_s{0.0}, current_backoff_s{0.0};
    std::atomic<bool> connected{false};
  };

  void Run();
  void PollOnce();
  void ExecuteWrites();
  void ExecuteWrite(const WriteRequest& request);
  void Notify();
  void CountReplyFault(const PlcStatus& status);
  /// Waits until `deadline_s` (steady seconds), running writes that arrive; false when stopping.
  bool WaitUntil(double deadline_s);
  double SteadyNow() const;

  PollerConfig config_;
  std::unique_ptr<PlcPort> port_;
  std::function<void()> notify_;
  ReadPlan plan_;

  // Poller-thread state.
  std::vector<uint16_t> block_registers_;  // all blocks back to back
  std::vector<int> block_offsets_;
  std::vector<char> block_ok_;                   // per block, this poll
  std::vector<core::SetpointLimiter> limiters_;  // one per channel (unused if not writable)
  PollSample current_;
  int64_t sequence_ = 0;
  int consecutive_timeouts_ = 0;
  bool ever_connected_ = false;

  SpscRing<PollSample> samples_;
  SpscRing<WriteResult> results_;
  AtomicCounters counters_;

  std::mutex mutex_;  // guards stop_, write queue
  std::condition_variable wake_;
  bool stop_ = false;
  std::vector<WriteRequest> write_queue_;  // ring, fixed capacity
  std::size_t write_head_ = 0;
  std::size_t write_count_ = 0;
  uint64_t next_write_id_ = 1;

  std::thread thread_;
};

}  // namespace canalid::drivers
