#include "drivers/lcm/fake_bus.h"

#include <algorithm>

namespace canalid::drivers {

bool FakeBus::Publish(const std::string& channel, std::span<const uint8_t> data) noexcept {
  if (publish_fails_) return false;
  try {
    published_.push_back({channel, std::vector<uint8_t>(data.begin(), data.end())});
    for (Entry& e : entries_) {
      if (!std::regex_match(channel, e.pattern)) continue;
      if (static_cast<int>(e.pending.size()) >= e.capacity) {
        ++dropped_;
        continue;
      }
      e.pending.push_back(published_.size() - 1);
    }
    return true;
  } catch (...) {
    return false;
  }
}

int FakeBus::Subscribe(const std::string& channel_regex, RawHandler handler, int queue_capacity) {
  Entry e;
  e.id = next_id_++;
  e.pattern = std::regex(channel_regex, std::regex::extended);
  e.handler = std::move(handler);
  e.capacity = std::max(queue_capacity, 1);
  entries_.push_back(std::move(e));
  return entries_.back().id;
}

void FakeBus::Unsubscribe(int id) noexcept {
  std::erase_if(entries_, [id](const Entry& e) { return e.id == id; });
}

int FakeBus::Handle(double /*timeout_s*/) noexcept {
  // Deliver in publish order across subscriptions, as LCM dispatches messages one by one.
  int handled = 0;
  while (true) {
    Entry* next = nullptr;
    for (Entry& e : entries_) {
      if (!e.pending.empty() && (next == nullptr || e.pending.front() < next->pending.front())) {
        next = &e;
      }
    }
    if (next == nullptr) return handled;
    const Message& m = published_[next->pending.front()];
    next->pending.pop_front();
    ++handled;
    try {
      if (!next->handler(m.channel, m.data)) ++failures_;
    } catch (...) {
      ++failures_;
    }
  }
}

}  // namespace canalid::drivers
