// `canalsim serve --rtu`: Modbus RTU over a pseudo-terminal pair.  The test plays socat: two
// ptys whose master sides a thread relays to each other; the server opens one slave side, a
// libmodbus RTU master the other.  Lockstep mode; expected values as in serve_test.cc.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "tests/sim/serve_process.h"
#include "tests/support/run_program.h"

namespace canalid::testing {
namespace {

/// Two ptys joined back to back (what `socat pty pty` does).
class PtyPair {
 public:
  PtyPair() {
    termios raw{};
    cfmakeraw(&raw);
    char name[2][128];
    for (int i = 0; i < 2; ++i) {
      if (openpty(&master_[i], &slave_[i], name[i], &raw, nullptr) != 0) {
        throw std::runtime_error("openpty failed");
      }
      fcntl(master_[i], F_SETFD, FD_CLOEXEC);
      fcntl(slave_[i], F_SETFD, FD_CLOEXEC);
      path_[i] = name[i];
    }
    if (pipe2(wake_, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    relay_ = std::thread([this] { Relay(); });
  }
  ~PtyPair() {
    const char x = 0;
    [[maybe_unused]] const ssize_t w = write(wake_[1], &x, 1);
    relay_.join();
    for (int fd : {master_[0], master_[1], slave_[0], slave_[1], wake_[0], wake_[1]}) close(fd);
  }
  const std::string& path(int i) const { return path_[i]; }

 private:
  void Relay() {
    char buffer[512];
    for (;;) {
      pollfd p[3] = {{master_[0], POLLIN, 0}, {master_[1], POLLIN, 0}, {wake_[0], POLLIN, 0}};
      if (poll(p, 3, -1) < 0) continue;
      if (p[2].revents != 0) return;
      for (int i = 0; i < 2; ++i) {
        if ((p[i].revents & POLLIN) == 0) continue;
        const ssize_t n = read(master_[i], buffer, sizeof(buffer));
        if (n > 0) {
          [[maybe_unused]] const ssize_t w = write(master_[1 - i], buffer, static_cast<size_t>(n));
        }
      }
    }
  }
  int master_[2] = {-1, -1};
  int slave_[2] = {-1, -1};
  int wake_[2] = {-1, -1};
  std::string path_[2];
  std::thread relay_;
};

class RtuMaster {
 public:
  RtuMaster(const std::string& device, int unit) {
    ctx_ = modbus_new_rtu(device.c_str(), 19200, 'E', 8, 1);
    if (ctx_ == nullptr) throw std::runtime_error("modbus_new_rtu failed");
    modbus_set_slave(ctx_, unit);
    modbus_set_response_timeout(ctx_, 5, 0);
    if (modbus_connect(ctx_) != 0) throw std::runtime_error("RTU connect failed");
  }
  ~RtuMaster() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  modbus_t* ctx() { return ctx_; }

 private:
  modbus_t* ctx_;
};

class ServeRtuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TestDirectory(std::string("serve_rtu_") +
                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    server_ = std::make_unique<ServeProcess>(
        std::vector<std::string>{"--canal", SourcePath("config/sim/asce-canal2.toml"), "--plc",
                                 SourcePath("config/sim/plc/asce2.toml"), "--lockstep", "--rtu",
                                 ptys_.path(0), "--unit-id", "7"},
        dir_ / "stderr.txt");
  }
  void TearDown() override { EXPECT_EQ(server_->Stop(), 0) << ReadFile(dir_ / "stderr.txt"); }
  PtyPair ptys_;
  std::filesystem::path dir_;
  std::unique_ptr<ServeProcess> server_;
};

TEST_F(ServeRtuTest, RtuAndTcpMastersSeeTheSamePlc) {
  EXPECT_NE(server_->ready_line().find("RTU " + ptys_.path(0) + " 19200 8E1 unit 7"),
            std::string::npos)
      << server_->ready_line();
  RtuMaster rtu(ptys_.path(1), 7);
  Master tcp(server_->port());
  std::uint16_t r[16];
  ASSERT_EQ(modbus_read_input_registers(rtu.ctx(), 7, 1, r), 1) << modbus_strerror(errno);
  EXPECT_EQ(r[0], 8);  // pool count
  ASSERT_EQ(modbus_read_input_registers(rtu.ctx(), 110, 1, r), 1) << modbus_strerror(errno);
  EXPECT_NEAR(r[0], 2100, 1);  // pool 2 downstream level, mm
  // A step commanded over RTU is seen over TCP, a setpoint written over TCP is read over RTU.
  ASSERT_EQ(modbus_write_register(rtu.ctx(), 1, 5), 1) << modbus_strerror(errno);
  EXPECT_EQ(tcp.Input(6), 5);
  tcp.Write(102, 1300);
  ASSERT_EQ(modbus_read_registers(rtu.ctx(), 102, 1, r), 1) << modbus_strerror(errno);
  EXPECT_EQ(r[0], 1300);
  ASSERT_EQ(modbus_read_input_registers(rtu.ctx(), 300, 16, r), 16) << modbus_strerror(errno);
  EXPECT_EQ(std::vector<std::uint16_t>(r, r + 16), tcp.Inputs(300, 16));
}

// Not tested: a request for another unit id.  The slave ignores it, but libmodbus's RTU slave
// then also ignores the next frame, taking it for the other unit's reply on a multi-drop line.
TEST_F(ServeRtuTest, FaultsApplyOnTheSerialLine) {
  RtuMaster rtu(ptys_.path(1), 7);
  std::uint16_t r[1];
  ASSERT_EQ(modbus_read_input_registers(rtu.ctx(), 7, 1, r), 1);
  modbus_set_response_timeout(rtu.ctx(), 5, 0);
  Master tcp(server_->port());
  tcp.Write(11, 4);  // every read answered with exception 4
  EXPECT_EQ(modbus_read_input_registers(rtu.ctx(), 7, 1, r), -1);
  EXPECT_EQ(errno, EMBXSFAIL);
  tcp.Write(11, 0);
  tcp.Write(12, 1);  // "drop": on a serial line the request gets no reply
  modbus_set_response_timeout(rtu.ctx(), 0, 300000);
  EXPECT_EQ(modbus_read_input_registers(rtu.ctx(), 7, 1, r), -1);
  EXPECT_EQ(errno, ETIMEDOUT);
  modbus_set_response_timeout(rtu.ctx(), 5, 0);
  ASSERT_EQ(modbus_read_input_registers(rtu.ctx(), 7, 1, r), 1) << modbus_strerror(errno);
  EXPECT_EQ(r[0], 8);
}

}  // namespace
}  // namespace canalid::testing
