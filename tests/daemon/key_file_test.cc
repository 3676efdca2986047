// ReadKeyFile: hex and raw keys, and every refusal (permissions, empty, short, missing).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "daemon/canalidd/key_file.h"
#include "support/run_program.h"

namespace canalid::daemon {
namespace {

class KeyFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = testing::TestDirectory(
      std::string("key_file.") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::path Write(const std::string& text, mode_t mode = 0600) {
    const auto path = dir_ / ("key" + std::to_string(next_++));
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

TEST_F(KeyFileTest, HexKeyWithTrailingNewline) {
  const auto key = ReadKeyFile(Write("00ff10Ab" + std::string(24, '1') + "\n"));
  ASSERT_EQ(key.size(), 16u);
  EXPECT_EQ(key[0], 0x00);
  EXPECT_EQ(key[1], 0xff);
  EXPECT_EQ(key[2], 0x10);
  EXPECT_EQ(key[3], 0xab);
  EXPECT_EQ(key[4], 0x11);
}

TEST_F(KeyFileTest, RawKeyIsTakenAsIs) {
  // Not hex (odd length and a 'g'): every byte, the newline included, is the key.
  const std::string raw = "a raw secret, not hex: g\n";
  const auto key = ReadKeyFile(Write(raw, 0400));
  EXPECT_EQ(std::string(key.begin(), key.end()), raw);
}

TEST_F(KeyFileTest, RefusesGroupOrOtherAccess) {
  const std::string hex(64, 'a');
  for (mode_t mode : {0640, 0620, 0604, 0602, 0644, 0666}) {
    const auto path = Write(hex, mode);
    const std::string why = Refusal(path);
    EXPECT_NE(why.find(path.string()), std::string::npos) << why;
    EXPECT_NE(why.find("chmod 600"), std::string::npos) << why;
  }
  // Execute bits for group/others do not expose the key's content.
  EXPECT_EQ(ReadKeyFile(Write(hex, 0611)).size(), 32u);
}

TEST_F(KeyFileTest, RefusesEmptyShortMissingAndDirectories) {
  EXPECT_NE(Refusal(Write("")).find("is empty"), std::string::npos);
  EXPECT_NE(Refusal(Write("0011223344\n")).find("at least 16"), std::string::npos);
  EXPECT_NE(Refusal(dir_ / "missing").find("cannot open"), std::string::npos);
  std::filesystem::create_directory(dir_ / "d");
  ::chmod((dir_ / "d").c_str(), 0700);
  EXPECT_NE(Refusal(dir_ / "d").find("not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace canalid::daemon
