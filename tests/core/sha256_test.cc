// SHA-256 and HMAC-SHA256 against the published example vectors (FIPS 180-4 examples from NIST's
// "Cryptographic Standards and Guidelines: Examples with Intermediate Values", RFC 4231 section 4)
// and against Python's hashlib/hmac on seeded random keys and messages of every length around the
// block boundaries. Digests are exact, so every comparison is exact.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/hmac.h"
#include "core/sha256.h"
#include "support/run_program.h"

namespace canalid::core {
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

TEST(Sha256, FipsExamples) {
  EXPECT_EQ(Hex(Sha256::Hash(Bytes("abc"))),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Hex(Sha256::Hash(Bytes(""))),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  // 448 bits: the padding needs a second block.
  EXPECT_EQ(Hex(Sha256::Hash(Bytes("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"))),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Hex(Sha256::Hash(Bytes("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklm"
                                   "noijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu"))),
            "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST(Sha256, MillionAsInOddPieces) {
  // One million 'a' fed in pieces of 1..97 bytes, so the buffering path is exercised.
  Sha256 sha;
  const std::vector<uint8_t> a = Repeat('a', 97);
  std::size_t left = 1000000;
  std::size_t piece = 1;
  while (left > 0) {
    const std::size_t n = std::min(left, piece);
    sha.Update(std::span<const uint8_t>(a.data(), n));
    left -= n;
    piece = piece % 97 + 1;
  }
  EXPECT_EQ(Hex(sha.Finish()), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(HmacSha256, Rfc4231TestCases) {
  std::vector<uint8_t> key4;
  for (int i = 1; i <= 25; ++i) key4.push_back(static_cast<uint8_t>(i));
  struct Case {
    std::vector<uint8_t> key, data;
    std::string mac;
  };
  const std::vector<Case> cases = {
      {Repeat(0x0b, 20), Bytes("Hi There"),
       "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7"},
      {Bytes("Jefe"), Bytes("what do ya want for nothing?"),
       "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"},
      {Repeat(0xaa, 20), Repeat(0xdd, 50),
       "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe"},
      {key4, Repeat(0xcd, 50), "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b"},
      // Key longer than the block: hashed first.
      {Repeat(0xaa, 131), Bytes("Test Using Larger Than Block-Size Key - Hash Key First"),
       "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54"},
      {Repeat(0xaa, 131),
       Bytes("This is a test using a larger than block-size key and a larger than block-size "
             "data. The key needs to be hashed before being used by the HMAC algorithm."),
       "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2"},
  };
  for (const Case& c : cases) EXPECT_EQ(Hex(HmacSha256::Mac(c.key, c.data)), c.mac);
  // Test case 5 publishes only the first 128 bits.
  EXPECT_EQ(Hex(HmacSha256::Mac(Repeat(0x0c, 20), Bytes("Test With Truncation"))).substr(0, 32),
            "a3b6167473100ee06e0c796c2955552b");
}

TEST(HmacSha256, ReusableAfterFinish) {
  HmacSha256 hmac(Bytes("Jefe"));
  hmac.Update(Bytes("what do ya "));
  hmac.Update(Bytes("want for nothing?"));
  const Sha256Digest first = hmac.Finish();
  hmac.Update(Bytes("what do ya want for nothing?"));
  EXPECT_EQ(hmac.Finish(), first);
  EXPECT_EQ(Hex(first), "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
}

TEST(ConstantTimeEqual, ComparesLengthAndEveryByte) {
  const std::vector<uint8_t> a = {1, 2, 3, 4};
  EXPECT_TRUE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3, 4}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{0, 2, 3, 4}));
  EXPECT_FALSE(ConstantTimeEqual(a, std::vector<uint8_t>{1, 2, 3, 5}));
  EXPECT_TRUE(ConstantTimeEqual(std::vector<uint8_t>{}, std::vector<uint8_t>{}));
}

TEST(Sha256, AgreesWithPythonOnRandomInputs) {
  // Lengths 0..200 cover 55/56/63/64/65 (padding spills into a second block) and multi-block
  // messages; keys 0..150 bytes cover short, block-sized and hashed keys.
  std::mt19937 rng(20261121);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> key_length(0, 150);
  const auto dir = testing::TestDirectory("sha256_python");
  std::ostringstream input;
  std::vector<std::string> expected;
  for (int length = 0; length <= 200; ++length) {
    std::vector<uint8_t> key(static_cast<std::size_t>(key_length(rng)));
    std::vector<uint8_t> message(static_cast<std::size_t>(length));
    for (auto& b : key) b = static_cast<uint8_t>(byte(rng));
    for (auto& b : message) b = static_cast<uint8_t>(byte(rng));
    input << Hex(key) << ' ' << Hex(message) << '\n';
    expected.push_back(Hex(Sha256::Hash(message)) + ' ' + Hex(HmacSha256::Mac(key, message)));
  }
  testing::WriteFile(dir / "input.txt", input.str());
  testing::WriteFile(dir / "check.py",
                     "import hashlib, hmac, sys\n"
                     "for line in open(sys.argv[1]):\n"
                     "    k, m = (bytes.fromhex(x) for x in line.split(' '))\n"
                     "    print(hashlib.sha256(m).hexdigest(),"
                     " hmac.new(k, m, hashlib.sha256).hexdigest())\n");
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
}  // namespace canalid::core
