// DecodeMessage (drivers/lcm/bus.h) against hostile array counts: lcm-gen's decoders size an
// array from its count field before reading the bytes, so a short message claiming 2^31 elements
// asks for tens of GB.  This executable replaces operator new to record the largest request made
// while decoding, and checks that no request exceeds a small multiple of the message, for every
// count field of every type; and that the walk before the decode (lcm_shapes.hpp, generated from
// the .lcm files) accepts exactly lcm-gen's own encodings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <span>
#include <vector>

#include "drivers/lcm/bus.h"
#include "tests/drivers/lcm_test_messages.h"

namespace {
std::size_t g_largest_request = 0;
}

// The replacements pair malloc with free on purpose; GCC cannot see that after inlining.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
// A request over 16 MiB is recorded and refused: without the walk the decoders' huge requests
// (8 GiB for 2^28 strings) would otherwise be served and zeroed, and could take the machine down
// instead of failing the test.
void* operator new(std::size_t size) {
  g_largest_request = std::max(g_largest_request, size);
  if (size > (std::size_t{16} << 20)) throw std::bad_alloc();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace canalid::drivers {
namespace {

template <class Message>
std::vector<uint8_t> Encode(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  EXPECT_EQ(message.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

// Overwrites the big-endian int32 at `offset` with `value`.
void PutInt32(std::vector<uint8_t>& bytes, std::size_t offset, uint32_t value) {
  for (int i = 0; i < 4; ++i) {
    bytes.at(offset + static_cast<std::size_t>(i)) = static_cast<uint8_t>(value >> (24 - 8 * i));
  }
}

// Offset of the int32 count that precedes the first element of an array: found by encoding the
// message with that count and with one element less and comparing (the count is where the two
// encodings first differ).
template <class Message, class Shrink>
std::size_t CountOffset(const Message& message, Shrink shrink) {
  Message smaller = message;
  shrink(smaller);
  const std::vector<uint8_t> a = Encode(message);
  const std::vector<uint8_t> b = Encode(smaller);
  std::size_t i = 0;
  while (i < a.size() && i < b.size() && a[i] == b[i]) ++i;
  // Counts below 256: only the count's last byte differs, and the count starts 3 bytes before.
  EXPECT_GE(i, 3U);
  return i - 3;
}

// Decodes `bytes` as Message and returns the largest single allocation it asked for.
template <class Message>
std::size_t LargestRequestDecoding(const std::vector<uint8_t>& bytes, bool* decoded) {
  Message message;
  g_largest_request = 0;
  *decoded = DecodeMessage(std::span<const uint8_t>(bytes), message);
  return g_largest_request;
}

template <class Message, class Shrink>
void ExpectHugeCountRefused(const Message& message, Shrink shrink, const char* what) {
  const std::size_t offset = CountOffset(message, shrink);
  for (const uint32_t count : {0x7fffffffU, 0x10000000U, 0x00100000U, 0xffffffffU}) {
    std::vector<uint8_t> bytes = Encode(message);
    PutInt32(bytes, offset, count);
    bool decoded = true;
    const std::size_t largest = LargestRequestDecoding<Message>(bytes, &decoded);
    EXPECT_FALSE(decoded) << what << " count " << count;
    // The message itself is a few hundred bytes; 64 kB leaves room for the decoder's own strings.
    EXPECT_LE(largest, 65536U) << what << " count " << count << ": a request of " << largest
                               << " bytes for a message of " << bytes.size();
  }
}

TEST(LcmDecodeBound, HugeArrayCountsAskForNoMoreThanTheMessage) {
  ExpectHugeCountRefused(
      testing::MakeModel(),
      [](model_snapshot_t& m) {
        --m.num_params;
        m.param_names.pop_back();
        m.param_values.pop_back();
        m.param_std_devs.pop_back();
      },
      "model_snapshot_t.num_params");
  ExpectHugeCountRefused(
      testing::MakeSample(7),
      [](sample_t& s) {
        --s.num_channels;
        s.channel_names.pop_back();
        s.values.pop_back();
        s.quality.pop_back();
      },
      "sample_t.num_channels");
  ExpectHugeCountRefused(
      testing::MakeHealth(),
      [](health_t& h) {
        --h.num_counters;
        h.counter_names.pop_back();
        h.counter_values.pop_back();
      },
      "health_t.num_counters");
  ExpectHugeCountRefused(
      testing::MakeHealth(),
      [](health_t& h) {
        --h.num_gauges;
        h.gauge_names.pop_back();
        h.gauge_values.pop_back();
      },
      "health_t.num_gauges");
  ExpectHugeCountRefused(
      testing::MakeCommand(),
      [](command_t& c) {
        --c.hmac_size;
        c.hmac.pop_back();
      },
      "command_t.hmac_size");
}

// The walk accepts lcm-gen's encoding of each type and nothing shorter or longer.
// (The test messages' ExpectEqual reads element 0 of each array: not for empty ones.)
template <class Message>
void ExpectWalkMatchesEncoding(const Message& message, const char* what,
                               bool compare_fields = true) {
  const std::vector<uint8_t> bytes = Encode(message);
  const auto* type = static_cast<const Message*>(nullptr);
  EXPECT_TRUE(lcm_shapes::Fits(type, bytes.data(), bytes.size())) << what;
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    EXPECT_FALSE(lcm_shapes::Fits(type, bytes.data(), n)) << what << " cut to " << n << " bytes";
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(lcm_shapes::Fits(type, longer.data(), longer.size())) << what << " plus a byte";
  Message decoded;
  EXPECT_TRUE(DecodeMessage(std::span<const uint8_t>(bytes), decoded)) << what;
  if (compare_fields) testing::ExpectEqual(message, decoded);
  EXPECT_EQ(Encode(decoded), bytes) << what << ": decoded and encoded again";
}

TEST(LcmDecodeBound, WalkAcceptsExactlyTheEncodingOfEveryType) {
  ExpectWalkMatchesEncoding(testing::MakeSample(3), "sample_t");
  ExpectWalkMatchesEncoding(testing::MakeModel(), "model_snapshot_t");
  ExpectWalkMatchesEncoding(testing::MakeExperiment(), "experiment_state_t");
  ExpectWalkMatchesEncoding(testing::MakeHealth(), "health_t");
  ExpectWalkMatchesEncoding(testing::MakeConfig(), "config_t");
  ExpectWalkMatchesEncoding(testing::MakeCommand(), "command_t");
  model_snapshot_t empty = testing::MakeModel();
  empty.num_params = 0;
  empty.param_names.clear();
  empty.param_values.clear();
  empty.param_std_devs.clear();
  ExpectWalkMatchesEncoding(empty, "model_snapshot_t without parameters", false);
}

// A string whose length field is 0 (lcm-gen would assign length - 1 = SIZE_MAX characters),
// negative, or running past the end is refused by the walk itself (lcm-gen's decoder refuses
// them too, by throwing or by its own check: DecodeMessage returns false either way).
TEST(LcmDecodeBound, BadStringLengthsAreRefused) {
  const config_t config = testing::MakeConfig();
  const std::vector<uint8_t> good = Encode(config);
  const std::size_t path_length_at = 8 + 8;  // fingerprint, utime
  for (const uint32_t length : {0U, 0x80000000U, static_cast<uint32_t>(good.size())}) {
    std::vector<uint8_t> bytes = good;
    PutInt32(bytes, path_length_at, length);
    EXPECT_FALSE(
        lcm_shapes::Fits(static_cast<const config_t*>(nullptr), bytes.data(), bytes.size()))
        << "length " << length;
    config_t decoded;
    EXPECT_FALSE(DecodeMessage(std::span<const uint8_t>(bytes), decoded)) << "length " << length;
  }
}

}  // namespace
}  // namespace canalid::drivers
