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

/// A Modbus TCP slave (libmodbus) serving a PlcSimulation to any number of masters at once.
/// One thread: a pselect loop over the listening socket and the client sockets, which also
/// steps the plant on its clock (unless the simulation is in lockstep mode) and sends the
/// replies held back by the response-delay fault.  Requests of one connection are answered in
/// order; a held-back request stops reading from its connection until it is answered.
/// Transport faults (register_map.h): read exception code, response delay, dropped connection.
class ModbusTcpSlave final {
 public:
  /// Binds and listens on host:port (port "0" picks a free one).
  /// @throws std::runtime_error naming the address and the system error.
  ModbusTcpSlave(PlcSimulation* simulation, const std::string& host, const std::string& port,
                 ClockOptions clock);
  ~ModbusTcpSlave();
  ModbusTcpSlave(const ModbusTcpSlave&) = delete;
  ModbusTcpSlave& operator=(const ModbusTcpSlave&) = delete;

  /// The port actually bound.
  int port() const { return port_; }
  /// Serves until *stop becomes non-zero.  SIGTERM and SIGINT should be blocked by the caller
  /// and their handler set *stop; `wait_mask` (the mask with them unblocked) is used while
  /// waiting, so that a signal is never lost between the check of *stop and the wait.
  /// @throws std::runtime_error on an unexpected error of the wait.
  void Run(const volatile std::sig_atomic_t* stop, const sigset_t* wait_mask);

 private:
  using Clock = std::chrono::steady_clock;
  struct Client {
    int fd = -1;
    bool pending = false;
    Clock::time_point due;
    std::vector<std::uint8_t> request;
    int request_length = 0;
  };
  void Accept();
  void Receive(Client* client);
  /// Answers one request; returns false if the connection must be closed.
  bool Answer(Client* client);
  void StepClock(Clock::time_point now);

  PlcSimulation* simulation_;
  ClockOptions clock_;
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t mapping_{};
  int listen_fd_ = -1;
  int port_ = 0;
  int header_length_ = 0;
  std::vector<Client> clients_;
  Clock::time_point start_;
  long clock_steps_ = 0;
  int overruns_ = 0;
};

}  // namespace canalid::sim::plc
