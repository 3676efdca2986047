#include "drivers/modbus/plc_poller.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace canalid::drivers {
namespace {

double WallNow() {
  using namespace std::chrono;
  return duration<double>(system_clock::now().time_since_epoch()).count();
}

std::vector<RegisterSpan> Spans(const std::vector<PollChannel>& channels) {
  std::vector<RegisterSpan> spans;
  spans.reserve(channels.size());
  for (const PollChannel& c : channels) {
    spans.push_back({c.kind, c.address, drivers::RegisterCount(c.scaling.type)});
  }
  return spans;
}

PollSample Prototype(std::size_t channels) {
  PollSample s;
  s.values.assign(channels, 0.0);
  s.quality.assign(channels, SampleQuality::kReadFailed);
  s.raw.assign(channels, {0, 0});
  return s;
}

SampleQuality QualityOf(drivers::ScalingError error) {
  switch (error) {
    case drivers::ScalingError::kNone:
      return SampleQuality::kValid;
    case drivers::ScalingError::kOutOfRange:
      return SampleQuality::kOutOfRange;
    case drivers::ScalingError::kNotFinite:
      return SampleQuality::kNotFinite;
    default:
      return SampleQuality::kReadFailed;
  }
}

}  // namespace

void ValidatePollerConfig(const PollerConfig& c, double response_timeout_s) {
  const std::string where = "poller '" + c.plc_name + "': ";
  if (c.channels.empty()) throw std::invalid_argument(where + "channels is empty");
  if (!(std::isfinite(c.period_s) && c.period_s > response_timeout_s && c.period_s > 0.0)) {
    throw std::invalid_argument(where + "period_s = " + std::to_string(c.period_s) +
                                " must be finite and longer than the response timeout " +
                                std::to_string(response_timeout_s) + " s");
  }
  ReconnectBackoff check(c.backoff_initial_s, c.backoff_max_s);
  if (c.timeouts_before_reconnect < 1 || c.sample_queue_capacity < 1 ||
      c.write_queue_capacity < 1) {
    throw std::invalid_argument(where +
                                "timeouts_before_reconnect, sample_queue_capacity and "
                                "write_queue_capacity must be >= 1");
  }
  for (std::size_t i = 0; i < c.channels.size(); ++i) {
    const PollChannel& ch = c.channels[i];
    const std::string name = where + "channel " + std::to_string(i) + " '" + ch.name + "': ";
    try {
      drivers::ValidateChannelScaling(ch.scaling);
      if (ch.writable) core::ValidateSetpointLimits(ch.limits);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(name + e.what());
    }
    if (ch.writable && ch.kind != RegisterKind::kHolding) {
      throw std::invalid_argument(name + "writable = true needs a holding register");
    }
  }
}

PlcPoller::PlcPoller(PollerConfig config, std::unique_ptr<PlcPort> port,
                     std::function<void()> notify)
    : config_(std::move(config)),
      port_(std::move(port)),
      notify_(std::move(notify)),
      plan_(PlanReads(Spans(config_.channels), config_.max_gap_registers)),
      current_(Prototype(config_.channels.size())),
      samples_(static_cast<std::size_t>(std::max(config_.sample_queue_capacity, 1)), current_),
      results_(static_cast<std::size_t>(std::max(config_.write_queue_capacity, 1)), WriteResult{}) {
  if (port_ == nullptr) throw std::invalid_argument("poller: port is null");
  ValidatePollerConfig(config_, port_->response_timeout_s());
  block_registers_.assign(static_cast<std::size_t>(plan_.total_registers), 0);
  block_ok_.assign(plan_.blocks.size(), 0);
  int offset = 0;
  for (const ReadBlock& b : plan_.blocks) {
    block_offsets_.push_back(offset);
    offset += b.count;
  }
  // Non-writable channels get an unused limiter with valid limits.
  const core::SetpointLimits unused{0.0, 0.0, std::numeric_limits<double>::infinity()};
  for (const PollChannel& c : config_.channels)
    limiters_.emplace_back(c.writable ? c.limits : unused);
  write_queue_.resize(static_cast<std::size_t>(config_.write_queue_capacity));
}

PlcPoller::~PlcPoller() { Stop(); }

void PlcPoller::Start() {
  if (thread_.joinable()) return;
  {
    std::lock_guard lock(mutex_);
    stop_ = false;
  }
  thread_ = std::thread([this] { Run(); });
}

void PlcPoller::Stop() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

double PlcPoller::SteadyNow() const {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

void PlcPoller::Notify() {
  if (!notify_) return;
  try {
    notify_();
  } catch (...) {
    counters_.notify_failures.fetch_add(1, std::memory_order_relaxed);
  }
}

bool PlcPoller::WaitUntil(double deadline_s) {
  using namespace std::chrono;
  const auto deadline =
      steady_clock::time_point(duration_cast<steady_clock::duration>(duration<double>(deadline_s)));
  std::unique_lock lock(mutex_);
  while (true) {
    if (stop_) return false;
    if (write_count_ > 0) {
      lock.unlock();
      ExecuteWrites();
      lock.lock();
      continue;
    }
    if (wake_.wait_until(lock, deadline) == std::cv_status::timeout) return !stop_;
  }
}

void PlcPoller::Run() {
  ReconnectBackoff backoff(config_.backoff_initial_s, config_.backoff_max_s);
  double next_poll_s = SteadyNow();
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stop_) break;
    }
    if (!port_->connected()) {
      counters_.connected.store(false);
      const PlcStatus s = port_->Connect();
      if (!s.ok()) {
        counters_.connect_failures.fetch_add(1, std::memory_order_relaxed);
        const double delay = backoff.NextDelay();
        counters_.current_backoff_s.store(delay);
        Notify();
        if (!WaitUntil(SteadyNow() + delay)) break;
        continue;
      }
      if (ever_connected_) counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
      ever_connected_ = true;
      // The PLC may have restarted with other setpoints: rate-limit from fresh readings.
      for (core::SetpointLimiter& limiter : limiters_) limiter.Forget();
      backoff.Reset();
      consecutive_timeouts_ = 0;
      counters_.current_backoff_s.store(0.0);
      counters_.connected.store(true);
      next_poll_s = SteadyNow();
      Notify();
    }
    PollOnce();
    ExecuteWrites();
    next_poll_s += config_.period_s;
    const double now = SteadyNow();
    if (next_poll_s < now) {
      // Late: skip the missed periods rather than bursting to catch up.
      counters_.overruns.fetch_add(1, std::memory_order_relaxed);
      next_poll_s += std::ceil((now - next_poll_s) / config_.period_s) * config_.period_s;
    }
    if (!WaitUntil(next_poll_s)) break;
  }
  port_->Close();
  counters_.connected.store(false);
}

void PlcPoller::PollOnce() {
  PollSample& s = current_;
  s.sequence = sequence_++;
  s.time_s = WallNow();
  s.status = PlcStatus::Ok();
  const double start_s = SteadyNow();
  for (std::size_t b = 0; b < plan_.blocks.size(); ++b) {
    const ReadBlock& block = plan_.blocks[b];
    std::span<uint16_t> out(block_registers_.data() + block_offsets_[b],
                            static_cast<std::size_t>(block.count));
    // Blocks after a lost link are not attempted, so not counted as read errors either.
    const bool attempted = port_->connected();
    const PlcStatus r = attempted ? port_->ReadRegisters(block.kind, block.start, out)
                                  : PlcStatus{PlcErrorKind::kDisconnected, 0, 0, ReplyFault::kNone};
    if (attempted) CountReplyFault(r);  // a skipped late reply comes with a good one too
    if (r.ok()) {
      counters_.block_reads_ok.fetch_add(1, std::memory_order_relaxed);
      consecutive_timeouts_ = 0;
    } else {
      if (attempted) {
        counters_.read_errors[static_cast<std::size_t>(r.kind)].fetch_add(
            1, std::memory_order_relaxed);
      }
      if (s.status.ok()) s.status = r;
      // Zero the block so a failed read can never be decoded as data.
      std::fill(out.begin(), out.end(), uint16_t{0});
      if (r.kind == PlcErrorKind::kTimeout &&
          ++consecutive_timeouts_ >= config_.timeouts_before_reconnect) {
        port_->Close();
      }
    }
    block_ok_[b] = r.ok() ? 1 : 0;
  }
  s.round_trip_s = SteadyNow() - start_s;
  counters_.last_round_trip_s.store(s.round_trip_s);
  counters_.polls.fetch_add(1, std::memory_order_relaxed);
  counters_.connected.store(port_->connected());

  const double steady_s = SteadyNow();
  for (std::size_t i = 0; i < config_.channels.size(); ++i) {
    const PollChannel& c = config_.channels[i];
    const ChannelLocation& loc = plan_.channels[i];
    const int n = drivers::RegisterCount(c.scaling.type);
    const uint16_t* regs =
        block_registers_.data() + block_offsets_[static_cast<std::size_t>(loc.block)] + loc.offset;
    s.raw[i] = {regs[0], n == 2 ? regs[1] : uint16_t{0}};
    if (!block_ok_[static_cast<std::size_t>(loc.block)]) {
      s.quality[i] = SampleQuality::kReadFailed;
      s.values[i] = 0.0;
      continue;
    }
    const drivers::DecodedValue d = drivers::DecodeChannel(
        c.scaling, std::span<const uint16_t>(regs, static_cast<std::size_t>(n)));
    s.quality[i] = QualityOf(d.error);
    s.values[i] = d.ok() ? d.value : 0.0;
    if (c.writable && d.ok() && !limiters_[i].has_reference())
      limiters_[i].Reset(d.value, steady_s);
  }

  PollSample* slot = samples_.BeginPush();
  if (slot == nullptr) {
    counters_.samples_dropped.fetch_add(1, std::memory_order_relaxed);
  } else {
    // Same-size vector assignment copies in place, without allocating.
    slot->sequence = s.sequence;
    slot->time_s = s.time_s;
    slot->round_trip_s = s.round_trip_s;
    slot->status = s.status;
    slot->values = s.values;
    slot->quality = s.quality;
    slot->raw = s.raw;
    samples_.CommitPush();
  }
  Notify();
}

WriteTicket PlcPoller::RequestWrite(int channel, double value) {
  WriteTicket ticket;
  if (channel < 0 || channel >= static_cast<int>(config_.channels.size())) {
    ticket.status = WriteQueueStatus::kUnknownChannel;
    return ticket;
  }
  if (!config_.channels[static_cast<std::size_t>(channel)].writable) {
    ticket.status = WriteQueueStatus::kNotWritable;
    return ticket;
  }
  {
    std::lock_guard lock(mutex_);
    if (write_count_ == write_queue_.size()) {
      ticket.status = WriteQueueStatus::kQueueFull;
      return ticket;
    }
    ticket.id = next_write_id_++;
    write_queue_[(write_head_ + write_count_) % write_queue_.size()] = {ticket.id, channel, value};
    ++write_count_;
  }
  wake_.notify_all();
  return ticket;
}

void PlcPoller::ExecuteWrites() {
  while (true) {
    WriteRequest request;
    {
      std::lock_guard lock(mutex_);
      if (write_count_ == 0) return;
      request = write_queue_[write_head_];
      write_head_ = (write_head_ + 1) % write_queue_.size();
      --write_count_;
    }
    ExecuteWrite(request);
  }
}

void PlcPoller::ExecuteWrite(const WriteRequest& request) {
  const auto i = static_cast<std::size_t>(request.channel);
  const PollChannel& c = config_.channels[i];
  WriteResult r;
  r.id = request.id;
  r.channel = request.channel;
  r.requested = request.value;
  r.time_s = WallNow();
  const double now_s = SteadyNow();
  const core::LimitedSetpoint limited = limiters_[i].Apply(request.value, now_s);
  r.clamped = limited.clamped;
  r.rate_limited = limited.rate_limited;
  if (limited.status == core::SetpointStatus::kNoReference) {
    r.outcome = WriteOutcome::kNoReference;
  } else if (limited.status == core::SetpointStatus::kNotFinite) {
    r.outcome = WriteOutcome::kNotFinite;
  } else {
    std::array<uint16_t, 2> regs{};
    const int n = drivers::RegisterCount(c.scaling.type);
    r.encode_error = drivers::EncodeChannel(
        c.scaling, limited.value, std::span<uint16_t>(regs.data(), static_cast<std::size_t>(n)));
    if (r.encode_error != drivers::ScalingError::kNone) {
      r.outcome = WriteOutcome::kEncodeFailed;
    } else {
      if (!port_->connected()) {
        r.plc = PlcStatus{PlcErrorKind::kDisconnected, 0, 0, ReplyFault::kNone};
      } else if (n == 1) {
        r.plc = port_->WriteRegister(c.address, regs[0]);
      } else {
        r.plc = port_->WriteRegisters(c.address, std::span<const uint16_t>(regs.data(), 2));
      }
      CountReplyFault(r.plc);
      if (r.plc.ok()) {
        r.outcome = WriteOutcome::kWritten;
        r.written = limited.value;
        limiters_[i].Reset(limited.value, now_s);
      } else {
        r.outcome = WriteOutcome::kPlcFailed;
      }
    }
  }
  (r.outcome == WriteOutcome::kWritten ? counters_.writes_ok : counters_.writes_failed)
      .fetch_add(1, std::memory_order_relaxed);
  if (WriteResult* slot = results_.BeginPush()) {
    *slot = r;
    results_.CommitPush();
  } else {
    counters_.write_results_dropped.fetch_add(1, std::memory_order_relaxed);
  }
  Notify();
}

void PlcPoller::CountReplyFault(const PlcStatus& status) {
  if (status.reply_fault != ReplyFault::kNone) {
    counters_.reply_faults[static_cast<std::size_t>(status.reply_fault)].fetch_add(
        1, std::memory_order_relaxed);
  }
}

PollerCounters PlcPoller::counters() const {
  PollerCounters c;
  c.polls = counters_.polls.load();
  c.block_reads_ok = counters_.block_reads_ok.load();
  for (std::size_t k = 0; k < c.read_errors.size(); ++k) {
    c.read_errors[k] = counters_.read_errors[k].load();
  }
  for (std::size_t k = 0; k < c.reply_faults.size(); ++k) {
    c.reply_faults[k] = counters_.reply_faults[k].load();
  }
  c.connect_failures = counters_.connect_failures.load();
  c.reconnects = counters_.reconnects.load();
  c.samples_dropped = counters_.samples_dropped.load();
  c.overruns = counters_.overruns.load();
  c.writes_ok = counters_.writes_ok.load();
  c.writes_failed = counters_.writes_failed.load();
  c.write_results_dropped = counters_.write_results_dropped.load();
  c.notify_failures = counters_.notify_failures.load();
  c.last_round_trip_s = counters_.last_round_trip_s.load();
  c.current_backoff_s = counters_.current_backoff_s.load();
  c.connected = counters_.connected.load();
  return c;
}

}  // namespace canalid::drivers
