// ReadKeyFile: the one accepted format (64 hex digits, an optional newline) and every refusal
// (permissions, missing, directory, empty, short, long, not hex, odd length, a 16-character
// password, trailing garbage), each naming the format and `openssl rand -hex 32`.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "daemon/canalidd/key_file.h"
#include "tests/support/run_program.h"

namespace canalid::daemon {
namespace {

class KeyFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = testing::TestDirectory(
      std::string("key_file.") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::path Write(const std::string& text, mode_t mode = 0600) {
    auto path = dir_ / ("key" + std::to_string(next_++));
    testing::WriteFile(path, text);
    ::chmod(path.c_str(), mode);
    return path;
  }
  // The message of the refusal, for checks on its content.
  std::string Refusal(const std::filesystem::path& path) {
    try {
      ReadKeyFile(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << path << " was accepted";
    return "";
  }
  int next_ = 0;
};

const std::string kHex = "00ff10Ab" + std::string(56, '1');

TEST_F(KeyFileTest, SixtyFourHexDigitsWithOrWithoutANewline) {
  for (const std::string& text : {kHex, kHex + "\n"}) {
    const drivers::SecretBytes key = ReadKeyFile(Write(text));
    ASSERT_EQ(key.size(), kCommandKeyBytes);
    const auto bytes = key.span();
    EXPECT_EQ(bytes[0], 0x00);
    EXPECT_EQ(bytes[1], 0xff);
    EXPECT_EQ(bytes[2], 0x10);
    EXPECT_EQ(bytes[3], 0xab);
    EXPECT_EQ(bytes[4], 0x11);
    EXPECT_EQ(bytes[31], 0x11);
  }
  EXPECT_EQ(ReadKeyFile(Write(kHex, 0400)).size(), kCommandKeyBytes);
}

TEST_F(KeyFileTest, RefusesGroupOrOtherAccess) {
  for (mode_t mode : {0640u, 0620u, 0604u, 0602u, 0644u, 0666u}) {
    const auto path = Write(kHex, mode);
    const std::string why = Refusal(path);
    EXPECT_NE(why.find(path.string()), std::string::npos) << why;
    EXPECT_NE(why.find("chmod 600"), std::string::npos) << why;
  }
  // Execute bits for group/others do not expose the key's content.
  EXPECT_EQ(ReadKeyFile(Write(kHex, 0611)).size(), kCommandKeyBytes);
}

// Every bad content is refused with the format and how to make a key; none is read some other
// way (main read a 16-character password as 8 bytes of hex, and non-hex files as raw keys).
TEST_F(KeyFileTest, RefusesEveryOtherContentNamingTheFormat) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "is empty"},
      {"\n", "0 hex digits"},
      {"0011223344\n", "10 hex digits"},
      {"0123456789abcdef", "16 hex digits"},         // 16 hex characters
      {"Passw0rdPassw0rd\n", "not a hex digit"},     // 16 alphanumerics
      {kHex.substr(0, 63) + "\n", "63 hex digits"},  // odd length
      {kHex + "0\n", "longer than a key"},
      {kHex + kHex, "longer than a key"},
      {kHex + "\nextra", "not a hex digit"},  // trailing garbage
      {kHex + " \n", "not a hex digit"},      // trailing space
      {kHex + "\r\n", "not a hex digit"},     // CRLF
      {"hex:" + kHex.substr(0, 60), "not a hex digit"},
      {std::string(31, 'a') + "g" + std::string(32, 'a'), "byte 32 is not a hex digit"},
  };
  for (const auto& [text, reason] : cases) {
    const std::string why = Refusal(Write(text));
    EXPECT_NE(why.find(reason), std::string::npos) << "'" << text << "': " << why;
    EXPECT_NE(why.find("64 hex digits"), std::string::npos) << why;
    EXPECT_NE(why.find("openssl rand -hex 32"), std::string::npos) << why;
  }
}

TEST_F(KeyFileTest, RefusesMissingFilesAndDirectoriesAndFollowsSymlinksToTheirChecks) {
  EXPECT_NE(Refusal(dir_ / "missing").find("cannot open"), std::string::npos);
  std::filesystem::create_directory(dir_ / "d");
  ::chmod((dir_ / "d").c_str(), 0700);
  EXPECT_NE(Refusal(dir_ / "d").find("not a regular file"), std::string::npos);
  // A symlink is followed: to a good key it reads it, to an open one it refuses.
  const auto good = Write(kHex);
  std::filesystem::create_symlink(good, dir_ / "link-good");
  EXPECT_EQ(ReadKeyFile(dir_ / "link-good").size(), kCommandKeyBytes);
  const auto open = Write(kHex, 0644);
  std::filesystem::create_symlink(open, dir_ / "link-open");
  EXPECT_NE(Refusal(dir_ / "link-open").find("chmod 600"), std::string::npos);
  std::filesystem::create_symlink(dir_ / "nowhere", dir_ / "link-dangling");
  EXPECT_NE(Refusal(dir_ / "link-dangling").find("cannot open"), std::string::npos);
}

TEST(SecretBytes, WipesOnWipeAndMovesWithoutACopy) {
  drivers::SecretBytes secret(std::vector<uint8_t>{1, 2, 3, 4});
  const uint8_t* data = secret.span().data();
  drivers::SecretBytes moved = std::move(secret);
  EXPECT_TRUE(secret.empty());  // NOLINT(bugprone-use-after-move): the moved-from state is tested
  EXPECT_EQ(moved.span().data(), data);
  std::span<uint8_t> bytes = moved.mutable_span();
  drivers::WipeBytes(bytes);
  EXPECT_EQ(bytes[0] | bytes[1] | bytes[2] | bytes[3], 0);
  moved.Wipe();
  EXPECT_TRUE(moved.empty());
}

}  // namespace
}  // namespace canalid::daemon
