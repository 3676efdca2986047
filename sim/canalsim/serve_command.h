#pragma once
#include <CLI/CLI.hpp>
#include <optional>
#include <string>

namespace canalid::sim {

/// `canalsim serve`: the canal behind an emulated PLC on a Modbus TCP slave, and optionally a
/// Modbus RTU slave on a serial device (docs/register-map.md).
/// Registers the sub-command and its options on construction; Run() after a successful parse.
class ServeCommand final {
 public:
  explicit ServeCommand(CLI::App& app);
  bool selected() const { return command_->parsed(); }
  /// Serves until SIGTERM/SIGINT.  Returns the exit code: 0 after a signal, 78 for a config or
  /// argument error (every problem on stderr as file:line:column), 69 if it cannot listen.
  int Run() const;

 private:
  CLI::App* command_;
  std::string canal_path_;
  std::string plc_path_;
  std::string listen_ = "127.0.0.1:1502";
  double time_scale_ = 1.0;
  bool lockstep_ = false;
  bool check_only_ = false;
  std::string rtu_device_;
  int rtu_baud_ = 19200;
  std::string rtu_format_ = "8E1";
  int unit_id_ = 1;
};

}  // namespace canalid::sim
