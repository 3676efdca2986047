// HMAC-SHA256 (OpenSSL's libcrypto behind drivers/auth/hmac.h) against the RFC 4231 section 4 test
// vectors and against Python's hmac on seeded random keys and messages of every length around the
// SHA-256 block boundaries; the tag compare on equal, altered and wrongly sized tags. Tags are
// exact, so every comparison is exact.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/auth/hmac.h"
#include "tests/support/run_program.h"

namespace canalid::drivers {
namespace {

std::vector<uint8_t> Bytes(const std::string& s) { return {s.begin(), s.end()}; }
std::vector<uint8_t> Repeat(uint8_t byte, std::size_t n) { return std::vector<uint8_t>(n, byte); }

std::string Hex(std::span<const uint8_t> bytes) {
  std::string out;
  char two[3];
  for (uint8_t b : bytes) {
    std::snprintf(two, sizeof two, "%02x", b);
    out += two;
  }
  return out;
}

TEST(HmacSha256, Rfc4231TestCases) {
  std::vector<uint8_t> key4;  // test case 4: 0x01, 0x02, ..., 0x19
  for (int i = 1; i <= 25; ++i) key4.push_back(static_cast<uint8_t>(i));
  struct Case {
    int number;
    std::vector<uint8_t> key, data;
    std::string mac;  // hex; test case 5 publishes only the first 128 bits (tag truncated)
  };
  const std::vector<Case> cases = {
      {1, Repeat(0x0b, 20), Bytes("Hi There"),
       "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7"},
      // A key shorter than the tag.
      {2, Bytes("Jefe"), Bytes("what do ya want for nothing?"),
       "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"},
      {3, Repeat(0xaa, 20), Repeat(0xdd, 50),
       "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe"},
      {4, key4, Repeat(0xcd, 50),
       "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b"},
      {5, Repeat(0x0c, 20), Bytes("Test With Truncation"), "a3b6167473100ee06e0c796c2955552b"},
      // A 131-byte key, longer than the 64-byte block: hashed first.
      {6, Repeat(0xaa, 131), Bytes("Test Using Larger Than Block-Size Key - Hash Key First"),
       "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54"},
      {7, Repeat(0xaa, 131),
       Bytes("This is a test using a larger than block-size key and a larger than block-size "
             "data. The key needs to be hashed before being used by the HMAC algorithm."),
       "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2"},
  };
  ASSERT_EQ(cases.size(), 7u);
  for (const Case& c : cases) {
    SCOPED_TRACE("RFC 4231 test case " + std::to_string(c.number));
    const std::string tag = Hex(HmacSha256::Mac(c.key, c.data));
    ASSERT_EQ(tag.size(), 64u);
    EXPECT_EQ(tag.substr(0, c.mac.size()), c.mac);
  }
}

TEST(HmacSha256, EmptyKeyAndMessage) {
  // RFC 2104 allows an empty key; Python: hmac.new(b"", b"", hashlib.sha256).hexdigest().
  EXPECT_EQ(Hex(HmacSha256::Mac({}, {})),
            "b613679a0814d9ec772f95d778c35fc5ff1697c493715653c6c712144292c5ad");
}

TEST(ConstantTimeEqual, ComparesLengthAndEveryByte) {
  const std::vector<uint8_t> a = {1, 2, 3, 4};
  EXPECT_TRUE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3, 4}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{0, 2, 3, 4}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3, 5}));
  EXPECT_TRUE(ConstantTimeEqual(std::vector<uint8_t>{}, std::vector<uint8_t>{}));
}

TEST(ConstantTimeEqual, RefusesATagDifferingInOneByteOrInLength) {
  const Sha256Digest tag = HmacSha256::Mac(Bytes("Jefe"), Bytes("what do ya want for nothing?"));
  const std::vector<uint8_t> same(tag.begin(), tag.end());
  EXPECT_TRUE(ConstantTimeEqual(tag, same));
  for (std::size_t i : {std::size_t{0}, std::size_t{15}, tag.size() - 1}) {
    std::vector<uint8_t> altered = same;
    altered[i] ^= 0x80;
    EXPECT_FALSE(ConstantTimeEqual(tag, altered)) << "byte " << i;
  }
  // A right prefix is not enough, and neither is the right tag with a byte more.
  EXPECT_FALSE(ConstantTimeEqual(tag, std::span<const uint8_t>(same.data(), same.size() - 1)));
  std::vector<uint8_t> longer = same;
  longer.push_back(0);
  EXPECT_FALSE(ConstantTimeEqual(tag, longer));
  EXPECT_FALSE(ConstantTimeEqual(tag, std::span<const uint8_t>()));
}

TEST(HmacSha256, AgreesWithPythonOnRandomInputs) {
  // Lengths 0..200 cover 55/56/63/64/65 (padding spills into a second block) and multi-block
  // messages; keys 0..150 bytes cover short, block-sized and hashed keys.
  std::mt19937 rng(20261121);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> key_length(0, 150);
  const auto dir = testing::TestDirectory("hmac_python");
  std::ostringstream input;
  std::vector<std::string> expected;
  for (int length = 0; length <= 200; ++length) {
    std::vector<uint8_t> key(static_cast<std::size_t>(key_length(rng)));
    std::vector<uint8_t> message(static_cast<std::size_t>(length));
    for (auto& b : key) b = static_cast<uint8_t>(byte(rng));
    for (auto& b : message) b = static_cast<uint8_t>(byte(rng));
    input << Hex(key) << ' ' << Hex(message) << '\n';
    expected.push_back(Hex(HmacSha256::Mac(key, message)));
  }
  testing::WriteFile(dir / "input.txt", input.str());
  testing::WriteFile(dir / "check.py",
                     "import hashlib, hmac, sys\n"
                     "for line in open(sys.argv[1]):\n"
                     "    k, m = (bytes.fromhex(x) for x in line.split(' '))\n"
                     "    print(hmac.new(k, m, hashlib.sha256).hexdigest())\n");
  const auto run = testing::RunProgram(
      "/usr/bin/python3 " + (dir / "check.py").string() + " " + (dir / "input.txt").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream lines(run.out);
  std::string line;
  std::size_t i = 0;
  while (std::getline(lines, line)) {
    ASSERT_LT(i, expected.size());
    EXPECT_EQ(line, expected[i]) << "message length " << i;
    ++i;
  }
  EXPECT_EQ(i, expected.size());
}

}  // namespace
}  // namespace canalid::drivers
