// Driver costs on loopback:
//   BM_ModbusRead125: one 125-register read round trip through ModbusPort (libmodbus client)
//     against an in-process libmodbus TCP server thread; median and p99 per read as counters.
//   BM_LcmPublishSample: encode + publish of a 16-channel canalid.sample_t over memq://.
//   BM_LcmPublishHandleSample: the same plus its delivery to a typed subscriber (Handle).
// Run: build/bench/modbus_bench --benchmark_repetitions=3 (the machine is shared: compare medians).
#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <canalid/sample_t.hpp>
#include <chrono>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "drivers/lcm/lcm_bus.h"
#include "drivers/modbus/modbus_port.h"

namespace {

using canalid::drivers::ModbusPort;
using canalid::drivers::ModbusTcpConfig;
using canalid::drivers::RegisterKind;

/// A libmodbus TCP server on an ephemeral loopback port serving 200 holding registers to one
/// client, on its own thread until the client disconnects.
class LoopbackServer {
 public:
  LoopbackServer() {
    listen_fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    if (bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
        getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0 ||
        listen(listen_fd_, 1) != 0) {
      throw std::runtime_error("modbus_bench: cannot listen on a loopback port");
    }
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { Serve(); });
  }
  ~LoopbackServer() {
    thread_.join();
    close(listen_fd_);
  }
  int port() const { return port_; }

 private:
  void Serve() {
    const int fd = accept(listen_fd_, nullptr, nullptr);
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port_);
    modbus_mapping_t* map = modbus_mapping_new(0, 0, 200, 0);
    for (int i = 0; i < 200; ++i) map->tab_registers[i] = static_cast<uint16_t>(i * 7);
    modbus_set_socket(ctx, fd);
    std::array<uint8_t, MODBUS_TCP_MAX_ADU_LENGTH> query{};
    while (true) {
      const int rc = modbus_receive(ctx, query.data());
      if (rc > 0) {
        modbus_reply(ctx, query.data(), rc, map);
      } else if (rc == -1) {
        break;  // client gone
      }
    }
    modbus_mapping_free(map);
    modbus_close(ctx);
    modbus_free(ctx);
  }

  int listen_fd_ = -1;
  int port_ = 0;
  std::thread thread_;
};

void SetPercentiles(benchmark::State& state, std::vector<double>& us) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
}

void BM_ModbusRead125(benchmark::State& state) {
  LoopbackServer server;
  {
    ModbusTcpConfig config;
    config.port = server.port();
    ModbusPort port(config);
    if (!port.Connect().ok()) {
      state.SkipWithError("connect failed");
      return;
    }
    std::array<uint16_t, 125> regs{};
    std::vector<double> us;
    us.reserve(1 << 20);
    for (auto _ : state) {
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = port.ReadRegisters(RegisterKind::kHolding, 0, regs).ok();
      const auto t1 = std::chrono::steady_clock::now();
      if (!ok || regs[124] != 124 * 7) {
        state.SkipWithError("read failed");
        break;
      }
      us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    }
    SetPercentiles(state, us);
  }  // the port closes, so the server thread ends
}
BENCHMARK(BM_ModbusRead125)->UseRealTime();

canalid::sample_t Sample16() {
  canalid::sample_t m;
  m.source = "plc.pool2";
  m.reach = "pool2";
  m.num_channels = 16;
  for (int i = 0; i < 16; ++i) {
    m.channel_names.push_back("ch" + std::to_string(i) + ".level_m");
    m.values.push_back(1.0 + i);
    m.quality.push_back(0);
  }
  return m;
}

void BM_LcmPublishSample(benchmark::State& state) {
  canalid::drivers::LcmBus bus("memq://");
  canalid::sample_t m = Sample16();
  std::vector<uint8_t> buffer;
  std::vector<double> us;
  us.reserve(1 << 20);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    ++m.sequence;
    const bool ok = canalid::drivers::PublishMessage(bus, "CANALID_SAMPLE_pool2", m, buffer);
    const auto t1 = std::chrono::steady_clock::now();
    if (!ok) {
      state.SkipWithError("publish failed");
      break;
    }
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  state.counters["bytes"] = m.getEncodedSize();
  SetPercentiles(state, us);
}
BENCHMARK(BM_LcmPublishSample);

void BM_LcmPublishHandleSample(benchmark::State& state) {
  canalid::drivers::LcmBus bus("memq://");
  int64_t received = 0;
  canalid::drivers::SubscribeMessage<canalid::sample_t>(
      bus, "CANALID_SAMPLE_.*", [&](const std::string&, const canalid::sample_t&) { ++received; });
  canalid::sample_t m = Sample16();
  std::vector<uint8_t> buffer;
  for (auto _ : state) {
    ++m.sequence;
    canalid::drivers::PublishMessage(bus, "CANALID_SAMPLE_pool2", m, buffer);
    bus.Handle(1.0);
  }
  if (received != static_cast<int64_t>(state.iterations())) state.SkipWithError("lost messages");
}
BENCHMARK(BM_LcmPublishHandleSample);

}  // namespace
