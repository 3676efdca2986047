// The results server against real masters: libmodbus (its own float helper decodes the words),
// pymodbus and mbpoll; writes refused with exception 1; 50 masters at once; masters that misbehave.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/results/results_image.h"
#include "core/results/results_layout.h"
#include "drivers/modbus/results_server.h"
#include "tests/support/loopback_port.h"
#include "tests/support/run_program.h"

namespace canalid::drivers {
namespace {

using namespace std::chrono_literals;
using testing::ConnectLoopback;

double WallNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

int ParamAddress(int reach, const std::string& kind, bool batch, int index) {
  const core::ResultsKind& k = *core::FindResultsKind(kind);
  return core::ResultsSlotAddress(reach, k, batch) + core::kResultsSlotHeaderWords +
         core::kResultsWordsPerParam * index;
}

class Master {
 public:
  explicit Master(int port) : ctx_(modbus_new_tcp("127.0.0.1", port)) {
    modbus_set_response_timeout(ctx_, 5, 0);
    connected_ = modbus_connect(ctx_) == 0;
  }
  ~Master() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  Master(const Master&) = delete;
  Master& operator=(const Master&) = delete;
  bool connected() const { return connected_; }
  modbus_t* ctx() { return ctx_; }

 private:
  modbus_t* ctx_;
  bool connected_ = false;
};

// Sends `bytes` on `fd` and reads `count` bytes back (at most 5 s); what it read.
std::vector<std::uint8_t> Exchange(int fd, const std::vector<std::uint8_t>& bytes,
                                   std::size_t count) {
  EXPECT_EQ(send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL), static_cast<ssize_t>(bytes.size()));
  const timeval timeout{5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<std::uint8_t> got(count);
  std::size_t have = 0;
  while (have < count) {
    const ssize_t n = recv(fd, got.data() + have, count - have, 0);
    if (n <= 0) break;
    have += static_cast<std::size_t>(n);
  }
  got.resize(have);
  return got;
}

class ResultsServerTest : public ::testing::Test {
 protected:
  void Start(int max_clients = 64, double frame_timeout_s = 1.0, double idle_timeout_s = 60.0) {
    core::ResultsImage image({"pool1", "pool2"}, WallNow() - 100.0);
    ResultsServerOptions options;
    options.port = "0";
    options.max_clients = max_clients;
    options.frame_timeout_s = frame_timeout_s;
    options.idle_timeout_s = idle_timeout_s;
    server_ = std::make_unique<ResultsServer>(std::move(image), options);
    ASSERT_GT(server_->port(), 0);
    server_->Update([&](core::ResultsImage& im) {
      ASSERT_TRUE(im.SetModel(
          1, {"id", "rls-bank", WallNow() - 30.0, 4321, names_, values_, std_devs_, 0, 0.004}));
    });
  }
  // Waits (at most 10 s) until `done()`.
  template <class Done>
  static bool WaitFor(Done done) {
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (!done()) {
      if (std::chrono::steady_clock::now() > end) return false;
      std::this_thread::sleep_for(10ms);
    }
    return true;
  }

  std::vector<std::string> names_{"delay_s", "area_m2"};
  std::vector<double> values_{660.0, 32954.25};
  std::vector<double> std_devs_{0.0, 912.5};
  std::unique_ptr<ResultsServer> server_;
};

TEST_F(ResultsServerTest, LibmodbusReadsHoldingAndInputRegistersAlike) {
  Start();
  Master m(server_->port());
  ASSERT_TRUE(m.connected());
  const int at = ParamAddress(1, "id", false, 0);
  std::uint16_t holding[8];
  std::uint16_t input[8];
  ASSERT_EQ(modbus_read_registers(m.ctx(), at, 8, holding), 8) << modbus_strerror(errno);
  ASSERT_EQ(modbus_read_input_registers(m.ctx(), at, 8, input), 8) << modbus_strerror(errno);
  EXPECT_EQ(modbus_get_float_abcd(holding), 660.0f);
  EXPECT_EQ(modbus_get_float_abcd(holding + 2), 0.0f);
  EXPECT_EQ(modbus_get_float_abcd(holding + 4), 32954.25f);
  EXPECT_EQ(modbus_get_float_abcd(holding + 6), 912.5f);
  EXPECT_EQ(std::vector<std::uint16_t>(holding, holding + 8),
            std::vector<std::uint16_t>(input, input + 8));
  // The slot's age is computed when asked: 30 s and counting.
  std::uint16_t age[2];
  const int slot = core::ResultsSlotAddress(1, *core::FindResultsKind("id"), false);
  ASSERT_EQ(modbus_read_registers(m.ctx(), slot + core::kSlotAge, 2, age), 2);
  EXPECT_GE(modbus_get_float_abcd(age), 30.0f);
  EXPECT_LT(modbus_get_float_abcd(age), 90.0f);
  std::uint16_t header[core::kHeaderWords];
  ASSERT_EQ(modbus_read_input_registers(m.ctx(), 0, core::kHeaderWords, header),
            core::kHeaderWords);
  EXPECT_EQ(header[core::kHeaderReachCount], 2);
  EXPECT_GE((header[core::kHeaderUptime] << 16) | header[core::kHeaderUptime + 1], 100);
  EXPECT_EQ(server_->counters().requests, 4);
}

// The probe a reload runs before it moves the map: a port in use, an unknown host are problems.
TEST_F(ResultsServerTest, ListenProblemNamesAnAddressInUse) {
  Start();
  const std::string problem = ResultsListenProblem("127.0.0.1", std::to_string(server_->port()));
  EXPECT_NE(problem.find("in use"), std::string::npos) << problem;
  EXPECT_EQ(ResultsListenProblem("127.0.0.1", "0"), "");
  EXPECT_NE(ResultsListenProblem("no-such-host.invalid", "1503"), "");
}

TEST_F(ResultsServerTest, EveryWriteIsRefusedWithIllegalFunction) {
  Start();
  Master m(server_->port());
  ASSERT_TRUE(m.connected());
  const int at = ParamAddress(1, "id", false, 0);
  const std::uint16_t values[2] = {1, 2};
  std::uint16_t read[2];
  const std::uint8_t bits[2] = {1, 0};
  EXPECT_EQ(modbus_write_register(m.ctx(), at, 1), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_registers(m.ctx(), at, 2, values), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_bit(m.ctx(), 0, 1), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_bits(m.ctx(), 0, 2, bits), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_mask_write_register(m.ctx(), at, 0, 1), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_and_read_registers(m.ctx(), at, 2, values, at, 2, read), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  ASSERT_EQ(modbus_read_registers(m.ctx(), at, 2, read), 2);
  EXPECT_EQ(modbus_get_float_abcd(read), 660.0f);  // unchanged
  EXPECT_EQ(server_->counters().refused_writes, 6);
}

TEST_F(ResultsServerTest, AddressesOutsideTheImageAreIllegalAndBitsDoNotExist) {
  Start();
  Master m(server_->port());
  ASSERT_TRUE(m.connected());
  const int size = core::ResultsImageWords(2);
  std::uint16_t words[4];
  std::uint8_t bits[4];
  EXPECT_EQ(modbus_read_registers(m.ctx(), size - 2, 4, words), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_input_registers(m.ctx(), 65000, 1, words), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_bits(m.ctx(), 0, 4, bits), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_read_input_bits(m.ctx(), 0, 4, bits), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_read_registers(m.ctx(), size - 4, 4, words), 4);  // the last words are there
}

TEST_F(ResultsServerTest, PymodbusAndMbpollReadTheSlot) {
  Start();
  const int at = ParamAddress(1, "id", false, 0);
  const auto dir = testing::TestDirectory("results_server_pymodbus");
  const testing::ProgramRun py = testing::RunProgramWithin(
      "/usr/bin/python3 " + std::string(CANALID_SOURCE_DIR) +
          "/tests/drivers/results_map_pymodbus.py " + std::to_string(server_->port()) + " " +
          std::to_string(at) + " 8",
      dir, 60);
  ASSERT_EQ(py.exit_code, 0) << py.out << py.err;
  const nlohmann::json j = nlohmann::json::parse(py.out);
  EXPECT_EQ(j["floats"][0].get<double>(), 660.0);
  EXPECT_EQ(j["floats"][2].get<double>(), 32954.25);
  EXPECT_EQ(j["floats"][3].get<double>(), 912.5);
  EXPECT_EQ(j["holding"], j["input"]);
  EXPECT_EQ(j["write_exception"].get<int>(), 1);
  EXPECT_EQ(j["write_multiple_exception"].get<int>(), 1);

  // mbpoll: 0-based references (-0), f32 big-endian words (-B), input registers (-t 3:float).
  const std::string base =
      "mbpoll -m tcp -a 1 -p " + std::to_string(server_->port()) + " -1 -o 5 -0 ";
  const testing::ProgramRun read = testing::RunProgramWithin(
      base + "-B -t 3:float -r " + std::to_string(at + 4) + " -c 1 127.0.0.1", dir, 30);
  EXPECT_NE(read.out.find("32954.2"), std::string::npos) << read.out << read.err;
  const testing::ProgramRun write =
      testing::RunProgramWithin(base + "-t 4 -r " + std::to_string(at) + " 127.0.0.1 7", dir, 30);
  EXPECT_NE(write.exit_code, 0) << write.out << write.err;
  EXPECT_NE((write.out + write.err).find("Illegal function"), std::string::npos)
      << write.out << write.err;
}

TEST_F(ResultsServerTest, FiftyMastersAtOnceAreAllAnswered) {
  Start();
  constexpr int kMasters = 50;
  constexpr int kReads = 100;
  std::atomic<int> good{0};
  std::vector<std::thread> threads;
  threads.reserve(kMasters);
  const int at = ParamAddress(1, "id", false, 0);
  for (int i = 0; i < kMasters; ++i) {
    threads.emplace_back([&] {
      Master m(server_->port());
      if (!m.connected()) return;
      std::uint16_t words[4];
      for (int k = 0; k < kReads; ++k) {
        if (modbus_read_registers(m.ctx(), at, 4, words) == 4 &&
            modbus_get_float_abcd(words) == 660.0f) {
          good.fetch_add(1);
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(good.load(), kMasters * kReads);
  EXPECT_EQ(server_->counters().clients_accepted, kMasters);
  EXPECT_EQ(server_->counters().requests, kMasters * kReads);
  EXPECT_TRUE(WaitFor([&] { return server_->counters().clients_connected == 0; }));
}

TEST_F(ResultsServerTest, MastersBeyondTheLimitAreRefused) {
  Start(2);
  Master a(server_->port()), b(server_->port());
  std::uint16_t w[1];
  ASSERT_EQ(modbus_read_registers(a.ctx(), 0, 1, w), 1);
  ASSERT_EQ(modbus_read_registers(b.ctx(), 0, 1, w), 1);
  Master c(server_->port());
  EXPECT_EQ(modbus_read_registers(c.ctx(), 0, 1, w), -1);
  EXPECT_TRUE(WaitFor([&] { return server_->counters().clients_refused == 1; }));
  EXPECT_EQ(modbus_read_registers(a.ctx(), 0, 1, w), 1);
}

// Requests the map has no data for are answered with an exception at once, and the next request
// on the same connection (sent in the same segment) is answered too: nothing is flushed.
TEST_F(ResultsServerTest, ExceptionsAreAnsweredAtOnceAndPipelinedRequestsAreKept) {
  Start();
  const int fd = ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  // Function 3 with count 0, function 8 (diagnostics), function 43 (device identification),
  // function 3 with count 126, then a good read of 1 register at 0, in one write.
  const std::vector<std::uint8_t> requests{
      0, 1, 0, 0, 0, 6, 1, 3,  0,  0, 0, 0,    // count 0
      0, 2, 0, 0, 0, 6, 1, 8,  0,  0, 0, 0,    // diagnostics
      0, 3, 0, 0, 0, 5, 1, 43, 14, 1, 0,       // read device identification
      0, 4, 0, 0, 0, 6, 1, 4,  0,  0, 0, 126,  // count 126
      0, 5, 0, 0, 0, 6, 1, 4,  0,  0, 0, 1};   // the map version
  // Four exception replies of 9 bytes, then 7 + 1 + 1 + 2.
  const std::vector<std::uint8_t> got = Exchange(fd, requests, 4 * 9 + 11);
  ASSERT_EQ(got.size(), 4u * 9 + 11);
  const std::vector<std::uint8_t> expected{0,
                                           1,
                                           0,
                                           0,
                                           0,
                                           3,
                                           1,
                                           0x83,
                                           3,
                                           0,
                                           2,
                                           0,
                                           0,
                                           0,
                                           3,
                                           1,
                                           0x88,
                                           1,
                                           0,
                                           3,
                                           0,
                                           0,
                                           0,
                                           3,
                                           1,
                                           0xAB,
                                           1,
                                           0,
                                           4,
                                           0,
                                           0,
                                           0,
                                           3,
                                           1,
                                           0x84,
                                           3,
                                           0,
                                           5,
                                           0,
                                           0,
                                           0,
                                           5,
                                           1,
                                           4,
                                           2,
                                           0,
                                           core::kResultsMapVersion};
  EXPECT_EQ(got, expected);
  close(fd);
  EXPECT_EQ(server_->counters().requests, 5);
  EXPECT_EQ(server_->counters().clients_dropped, 0);
}

// A master whose frame stops mid-way is dropped after the frame timeout; meanwhile another master
// is answered (the server never waits on one connection).
TEST_F(ResultsServerTest, AFrameThatStopsMidwayDropsOnlyItsConnection) {
  Start(64, 0.5);
  const int fd = ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  const std::uint8_t frame[] = {0, 1, 0, 0, 0, 6, 1, 3, 0};
  ASSERT_EQ(send(fd, frame, sizeof frame, 0), static_cast<ssize_t>(sizeof frame));
  Master m(server_->port());
  std::uint16_t w[1];
  for (int i = 0; i < 20; ++i) EXPECT_EQ(modbus_read_registers(m.ctx(), 0, 1, w), 1);
  EXPECT_TRUE(WaitFor([&] { return server_->counters().clients_dropped == 1; }));
  std::uint8_t byte = 0;
  EXPECT_EQ(recv(fd, &byte, 1, 0), 0);  // closed by the server
  close(fd);
  EXPECT_EQ(modbus_read_registers(m.ctx(), 0, 1, w), 1);
}

TEST_F(ResultsServerTest, AMalformedHeaderDropsItsConnection) {
  Start();
  for (const std::vector<std::uint8_t>& frame :
       {std::vector<std::uint8_t>{0, 1, 0, 7, 0, 6, 1, 3, 0, 0, 0, 1},  // protocol id 7
        std::vector<std::uint8_t>{0, 1, 0, 0, 0, 1, 1},                 // length 1
        std::vector<std::uint8_t>{0, 1, 0, 0, 1, 0, 1},                 // length 256
        std::vector<std::uint8_t>{0, 1, 0, 0, 0, 2, 1, 0x83}}) {        // an exception's code
    const int fd = ConnectLoopback(server_->port());
    ASSERT_GE(fd, 0);
    EXPECT_TRUE(Exchange(fd, frame, 1).empty());  // closed, no reply
    close(fd);
  }
  EXPECT_EQ(server_->counters().clients_dropped, 4);
  EXPECT_EQ(server_->counters().requests, 0);
}

// Connections left without a request are closed after the idle timeout, so that masters that
// went away do not hold the slots.
TEST_F(ResultsServerTest, IdleConnectionsAreClosed) {
  Start(2, 1.0, 0.3);
  const int a = ConnectLoopback(server_->port());
  const int b = ConnectLoopback(server_->port());
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  EXPECT_TRUE(WaitFor([&] { return server_->counters().clients_dropped == 2; }));
  std::uint8_t byte = 0;
  EXPECT_EQ(recv(a, &byte, 1, 0), 0);
  close(a);
  close(b);
  Master m(server_->port());
  std::uint16_t w[1];
  EXPECT_EQ(modbus_read_registers(m.ctx(), 0, 1, w), 1);
}

// A master that sends requests and never reads the replies fills its socket: the server drops it
// when a reply no longer fits (it never waits on the socket) and goes on answering the others.
// (Should the kernel stop delivering its requests first, with both queues full, the idle timeout,
// 3 s here, drops it instead.)
TEST_F(ResultsServerTest, AMasterThatNeverReadsIsDropped) {
  Start(64, 1.0, 3.0);
  const int fd = ConnectLoopback(server_->port());
  ASSERT_GE(fd, 0);
  const int small = 4096;
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  // Reads of 125 registers (259-byte replies), sent until the server closes the connection
  // (at most 30 s).
  std::vector<std::uint8_t> requests;
  for (int i = 0; i < 1000; ++i) {
    const std::uint8_t r[] = {static_cast<std::uint8_t>(i >> 8),
                              static_cast<std::uint8_t>(i),
                              0,
                              0,
                              0,
                              6,
                              1,
                              3,
                              0,
                              0,
                              0,
                              125};
    requests.insert(requests.end(), r, r + sizeof r);
  }
  std::atomic<bool> done{false};
  std::thread writer([&] {
    const timeval timeout{0, 200000};
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    const auto end = std::chrono::steady_clock::now() + 30s;
    std::size_t sent = 0;  // into `requests`, which is whole frames: restarting at 0 is aligned
    while (!done.load() && std::chrono::steady_clock::now() < end) {
      const ssize_t n = send(fd, requests.data() + sent, requests.size() - sent, MSG_NOSIGNAL);
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) break;  // closed by the server
      if (n > 0) sent = (sent + static_cast<std::size_t>(n)) % requests.size();
    }
  });
  EXPECT_TRUE(WaitFor([&] { return server_->counters().clients_dropped == 1; }))
      << server_->counters().requests << " requests answered";
  done.store(true);
  writer.join();
  Master m(server_->port());
  std::uint16_t w[1];
  EXPECT_EQ(modbus_read_registers(m.ctx(), 0, 1, w), 1) << modbus_strerror(errno);
  close(fd);
}

}  // namespace
}  // namespace canalid::drivers
