#include "sim/canalsim/serve_command.h"

#include <signal.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "sim/canal_config.h"
#include "sim/config_reader.h"
#include "sim/plc/modbus_slave.h"
#include "sim/plc/plc_config.h"
#include "sim/plc/plc_simulation.h"

namespace canalid::sim {
namespace {

constexpr int kExitUnavailable = 69;  // EX_UNAVAILABLE
constexpr int kExitSoftware = 70;     // EX_SOFTWARE
constexpr int kExitConfig = 78;       // EX_CONFIG

volatile std::sig_atomic_t g_stop = 0;

extern "C" void OnStopSignal(int) { g_stop = 1; }

// "host:port", "[v6]:port"; false if there is no port.
bool SplitListen(const std::string& text, std::string* host, std::string* port) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon + 1 == text.size()) return false;
  *host = text.substr(0, colon);
  *port = text.substr(colon + 1);
  if (host->size() >= 2 && host->front() == '[' && host->back() == ']') {
    *host = host->substr(1, host->size() - 2);
  }
  if (host->empty()) return false;
  for (char c : *port) {
    if (c < '0' || c > '9') return false;
  }
  return port->size() <= 5 && std::stoi(*port) <= 65535;
}

}  // namespace

ServeCommand::ServeCommand(CLI::App& app) {
  command_ = app.add_subcommand(
      "serve",
      "Run the canal in real or scaled time (or lockstep) behind an emulated PLC on a Modbus TCP "
      "slave; register map: docs/register-map.md");
  command_->add_option("--canal", canal_path_, "Canal TOML file (geometry, structures)")
      ->required()
      ->check(CLI::ExistingFile);
  command_
      ->add_option("--plc", plc_path_,
                   "PLC TOML file (pools, limits, rates, watchdog, encodings); default: every "
                   "pool, wide limits, no rate limit, no watchdog")
      ->check(CLI::ExistingFile);
  command_->add_option("--listen", listen_, "HOST:PORT to listen on (port 0 picks a free one)")
      ->capture_default_str();
  auto* scale =
      command_->add_option("--time-scale", time_scale_, "Plant seconds per wall-clock second")
          ->capture_default_str()
          ->check(CLI::PositiveNumber);
  command_
      ->add_flag("--lockstep", lockstep_,
                 "Step the plant only when a master writes the step register (holding 1)")
      ->excludes(scale);
  command_->add_option("--rtu", rtu_device_,
                       "Also serve Modbus RTU on this serial device (a tty or a pty)");
  command_->add_option("--rtu-baud", rtu_baud_, "RTU baud rate")
      ->capture_default_str()
      ->check(CLI::Range(300, 4000000));
  command_
      ->add_option("--rtu-format", rtu_format_,
                   "RTU data bits, parity (N, E, O) and stop bits, e.g. 8E1 or 8N2")
      ->capture_default_str();
  command_->add_option("--unit-id", unit_id_, "RTU slave address (TCP answers any unit id)")
      ->capture_default_str()
      ->check(CLI::Range(1, 247));
  command_->add_flag("--check-config", check_only_, "Validate the files and exit (0 or 78)");
}

int ServeCommand::Run() const {
  std::string host, port;
  if (!SplitListen(listen_, &host, &port)) {
    std::cerr << "canalsim: --listen '" << listen_
              << "' must be HOST:PORT with PORT in [0, 65535]\n";
    return kExitConfig;
  }
  plc::RtuOptions rtu;
  rtu.device = rtu_device_;
  rtu.baud = rtu_baud_;
  rtu.unit_id = unit_id_;
  if (rtu_format_.size() != 3 || (rtu_format_[0] != '7' && rtu_format_[0] != '8') ||
      std::string("NEO").find(rtu_format_[1]) == std::string::npos ||
      (rtu_format_[2] != '1' && rtu_format_[2] != '2')) {
    std::cerr << "canalsim: --rtu-format '" << rtu_format_
              << "' must be data bits (7, 8), parity (N, E, O), stop bits (1, 2), e.g. 8E1\n";
    return kExitConfig;
  }
  rtu.data_bits = rtu_format_[0] - '0';
  rtu.parity = rtu_format_[1];
  rtu.stop_bits = rtu_format_[2] - '0';
  Canal canal;
  plc::PlcConfig config;
  try {
    canal = LoadCanal(canal_path_);
    config =
        plc_path_.empty() ? plc::DefaultPlcConfig(canal) : plc::LoadPlcConfig(plc_path_, canal);
  } catch (const ConfigError& e) {
    for (const std::string& p : e.problems()) std::cerr << p << '\n';
    return kExitConfig;
  }
  std::unique_ptr<plc::PlcSimulation> simulation;
  try {
    simulation = std::make_unique<plc::PlcSimulation>(canal, config, lockstep_);
  } catch (const std::exception& e) {
    // An infeasible steady state or a PLC inconsistent with the canal is a configuration error.
    std::cerr << (plc_path_.empty() ? canal_path_ : plc_path_) << ": " << e.what() << '\n';
    return kExitConfig;
  }
  if (check_only_) {
    std::cerr << "canalsim: " << canal_path_ << (plc_path_.empty() ? "" : " and " + plc_path_)
              << " are valid\n";
    return 0;
  }
  // SIGTERM/SIGINT stay blocked except inside the wait, so none is lost between checks.
  sigset_t block, wait_mask;
  sigemptyset(&block);
  sigaddset(&block, SIGTERM);
  sigaddset(&block, SIGINT);
  pthread_sigmask(SIG_BLOCK, &block, &wait_mask);  // before any thread: they inherit it
  sigdelset(&wait_mask, SIGTERM);
  sigdelset(&wait_mask, SIGINT);
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  signal(SIGPIPE, SIG_IGN);
  try {
    plc::ModbusSlave slave(simulation.get(), plc::ClockOptions{time_scale_});
    const int bound = slave.ListenTcp(host, port);
    std::string rtu_text;
    if (!rtu.device.empty()) {
      slave.OpenRtu(rtu);
      rtu_text = " and RTU " + rtu.device + " " + std::to_string(rtu.baud) + " " + rtu_format_ +
                 " unit " + std::to_string(rtu.unit_id);
    }
    const bool v6 = host.find(':') != std::string::npos;
    char mode[64];
    std::snprintf(mode, sizeof(mode), lockstep_ ? "lockstep" : "time scale %g", time_scale_);
    // The ready line: printed once every port accepts requests.
    std::printf("canalsim: listening on %s%s%s:%d%s (%s, plant step %g s, %zu pools)\n",
                v6 ? "[" : "", host.c_str(), v6 ? "]" : "", bound, rtu_text.c_str(), mode,
                config.plant_step_s, config.pools.size());
    std::fflush(stdout);
    slave.Run(&g_stop, &wait_mask);
  } catch (const std::runtime_error& e) {
    std::cerr << "canalsim: " << e.what() << '\n';
    return g_stop != 0 ? 0 : kExitUnavailable;
  } catch (const std::exception& e) {
    std::cerr << "canalsim: " << e.what() << '\n';
    return kExitSoftware;
  }
  std::fprintf(stderr, "canalsim: stopped at plant time %.0f s after %ld steps\n",
               simulation->plant().time_s(), simulation->steps());
  return 0;
}

}  // namespace canalid::sim
