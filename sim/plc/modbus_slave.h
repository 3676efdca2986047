#pragma once
#include <modbus/modbus.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/plc/plc_simulation.h"

namespace canalid::sim::plc {

/// How the slave runs the plant clock.
struct ClockOptions {
  /// Plant seconds per wall-clock second (> 0); ignored in lockstep mode.
  double time_scale = 1.0;
};

/// A serial line for Modbus RTU.
struct RtuOptions {
  std::string device;  ///< e.g. /dev/ttyUSB0 or a pty such as /dev/pts/3
  int baud = 19200;
  char parity = 'E';  ///< 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  int unit_id = 1;  ///< the slave address this PLC answers on the line (1-247)
};

/// A Modbus slave (libmodbus) serving a PlcSimulation: a TCP listener with any number of masters
/// at once, and optionally one RTU serial line.  One thread: a pselect loop over the listening
/// socket, the client sockets and the serial line, which also steps the plant on its clock
/// (unless the simulation is in lockstep mode) and sends the replies held back by the
/// response-delay fault.  Requests of one connection are answered in order; a held-back request
/// stops reading from its connection until it is answered.  Transport faults (register_map.h):
/// read exception code, response delay, dropped connection (on the serial line: no reply).
class ModbusSlave final {
 public:
  /// @throws std::invalid_argument if time_scale <= 0.
  ModbusSlave(PlcSimulation* simulation, ClockOptions clock);
  ~ModbusSlave();
  ModbusSlave(const ModbusSlave&) = delete;
  ModbusSlave& operator=(const ModbusSlave&) = delete;

  /// Binds and listens on host:port (port "0" picks a free one); returns the port bound.
  /// @throws std::runtime_error naming the address and the system error.
  int ListenTcp(const std::string& host, const std::string& port);
  /// Opens and configures the serial device.  @throws std::runtime_error naming the device.
  void OpenRtu(const RtuOptions& options);

  /// Serves until *stop becomes non-zero.  SIGTERM and SIGINT should be blocked by the caller
  /// and their handler set *stop; `wait_mask` (the mask with them unblocked) is used while
  /// waiting, so that a signal is never lost between the check of *stop and the wait.
  /// @throws std::runtime_error on an unexpected error of the wait.
  void Run(const volatile std::sig_atomic_t* stop, const sigset_t* wait_mask);

 private:
  using Clock = std::chrono::steady_clock;
  struct Client {
    modbus_t* ctx = nullptr;  // the TCP or the RTU context
    int fd = -1;
    bool serial = false;
    bool pending = false;
    Clock::time_point due;
    std::vector<std::uint8_t> request;
    int request_length = 0;
  };
  void Accept();
  void Receive(Client* client);
  /// Answers one request; returns false if the connection must be closed.
  bool Answer(Client* client);
  void Close(Client* client);
  void StepClock(Clock::time_point now);

  PlcSimulation* simulation_;
  ClockOptions clock_;
  modbus_t* tcp_ = nullptr;
  modbus_t* rtu_ = nullptr;
  modbus_mapping_t mapping_{};
  int listen_fd_ = -1;
  std::vector<Client> clients_;
  Clock::time_point start_;
  long clock_steps_ = 0;
  int overruns_ = 0;
};

}  // namespace canalid::sim::plc
