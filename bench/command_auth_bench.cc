// Cost of authenticating one operator command (HMAC-SHA256 over its canonical bytes plus the
// checks) and raw HMAC-SHA256 throughput (OpenSSL's libcrypto). Commands are rare; this shows a
// flood of forgeries cannot starve the daemon's loop.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "drivers/auth/command_auth.h"
#include "drivers/auth/hmac.h"

namespace {

constexpr int64_t kNowUs = 1'763'700'000'000'000;

void BM_HmacSha256(benchmark::State& state) {
  const std::vector<uint8_t> key(32, 0x11);
  const std::vector<uint8_t> data(static_cast<std::size_t>(state.range(0)), 0x5a);
  for (auto _ : state) benchmark::DoNotOptimize(canalid::drivers::HmacSha256::Mac(key, data));
  state.SetBytesProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_HmacSha256)->Arg(64)->Arg(4096);

void BM_VerifyForgedCommand(benchmark::State& state) {
  const std::vector<uint8_t> key(32, 0x11);
  canalid::drivers::CommandAuthenticator auth({.enabled = true, .max_clock_skew_s = 30.0}, key);
  canalid::drivers::CommandFields fields;
  fields.utime_us = kNowUs;
  fields.counter = 1;
  fields.sender = "operator@scada1";
  fields.kind = 1;
  fields.reach = "pool2";
  fields.argument = "prbs";
  const auto mac = canalid::drivers::SignCommand(std::vector<uint8_t>(32, 0x22), fields);
  fields.mac = mac;
  for (auto _ : state) benchmark::DoNotOptimize(auth.Verify(fields, kNowUs));
}
BENCHMARK(BM_VerifyForgedCommand);

}  // namespace
