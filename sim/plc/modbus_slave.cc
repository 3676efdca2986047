#include "sim/plc/modbus_slave.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/system/errno_text.h"
#include "sim/plc/register_map.h"

namespace canalid::sim::plc {
namespace {

int Word(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }

bool IsRead(int function) {
  return function == MODBUS_FC_READ_COILS || function == MODBUS_FC_READ_DISCRETE_INPUTS ||
         function == MODBUS_FC_READ_HOLDING_REGISTERS ||
         function == MODBUS_FC_READ_INPUT_REGISTERS ||
         function == MODBUS_FC_WRITE_AND_READ_REGISTERS;
}

timespec ToTimespec(std::chrono::nanoseconds d) {
  if (d.count() < 0) d = std::chrono::nanoseconds(0);
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(d.count() / 1000000000);
  ts.tv_nsec = static_cast<long>(d.count() % 1000000000);
  return ts;
}

}  // namespace

ModbusSlave::ModbusSlave(PlcSimulation* simulation, ClockOptions clock)
    : simulation_(simulation), clock_(clock) {
  if (!(clock_.time_scale > 0.0)) {
    throw std::invalid_argument("time_scale = " + std::to_string(clock_.time_scale) +
                                " must be > 0");
  }
  // The mapping points into the simulation's register image (never freed by libmodbus).
  auto& input = simulation_->input_registers();
  auto& holding = simulation_->holding_registers();
  mapping_.nb_input_registers = static_cast<int>(input.size());
  mapping_.tab_input_registers = input.data();
  mapping_.nb_registers = static_cast<int>(holding.size());
  mapping_.tab_registers = holding.data();
  start_ = Clock::now();
}

int ModbusSlave::ListenTcp(const std::string& host, const std::string& port) {
  tcp_ = modbus_new_tcp_pi(host.c_str(), port.c_str());
  if (tcp_ == nullptr) {
    throw std::runtime_error("cannot create a Modbus TCP context for " + host + ":" + port + ": " +
                             modbus_strerror(errno));
  }
  listen_fd_ = modbus_tcp_pi_listen(tcp_, 32);
  if (listen_fd_ < 0) {
    throw std::runtime_error("cannot listen on " + host + ":" + port + ": " +
                             modbus_strerror(errno));
  }
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  int bound = 0;
  if (getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    if (address.ss_family == AF_INET) {
      bound = ntohs(reinterpret_cast<const sockaddr_in*>(&address)->sin_port);
    } else if (address.ss_family == AF_INET6) {
      bound = ntohs(reinterpret_cast<const sockaddr_in6*>(&address)->sin6_port);
    }
  }
  return bound;
}

void ModbusSlave::OpenRtu(const RtuOptions& o) {
  rtu_ = modbus_new_rtu(o.device.c_str(), o.baud, o.parity, o.data_bits, o.stop_bits);
  if (rtu_ == nullptr) {
    throw std::runtime_error("cannot create a Modbus RTU context for " + o.device + ": " +
                             modbus_strerror(errno));
  }
  if (modbus_set_slave(rtu_, o.unit_id) != 0 || modbus_connect(rtu_) != 0) {
    throw std::runtime_error("cannot open " + o.device +
                             " for Modbus RTU: " + modbus_strerror(errno));
  }
  Client c;
  c.ctx = rtu_;
  c.fd = modbus_get_socket(rtu_);
  c.serial = true;
  c.request.resize(MODBUS_RTU_MAX_ADU_LENGTH);
  clients_.push_back(std::move(c));
}

ModbusSlave::~ModbusSlave() {
  for (Client& c : clients_) {
    if (c.fd >= 0 && !c.serial) close(c.fd);
  }
  if (listen_fd_ >= 0) close(listen_fd_);
  if (tcp_ != nullptr) modbus_free(tcp_);
  if (rtu_ != nullptr) {
    modbus_close(rtu_);
    modbus_free(rtu_);
  }
}

void ModbusSlave::Close(Client* client) {
  if (client->serial) {
    // A serial line stays open: forget what was received and wait for the next frame.
    modbus_flush(client->ctx);
    client->pending = false;
    return;
  }
  close(client->fd);
  client->fd = -1;
}

void ModbusSlave::Accept() {
  const int fd = accept(listen_fd_, nullptr, nullptr);
  if (fd < 0) return;  // the peer went away before we accepted: nothing to serve
  if (fd >= FD_SETSIZE) {
    close(fd);
    return;
  }
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  Client c;
  c.ctx = tcp_;
  c.fd = fd;
  c.request.resize(MODBUS_TCP_MAX_ADU_LENGTH);
  clients_.push_back(std::move(c));
}

void ModbusSlave::Receive(Client* client) {
  if (!client->serial) modbus_set_socket(client->ctx, client->fd);
  const int rc = modbus_receive(client->ctx, client->request.data());
  if (rc < 0) {
    Close(client);  // peer closed or sent garbage: a PLC drops such a connection
    return;
  }
  if (rc == 0) return;  // addressed to another unit on the serial line
  client->request_length = rc;
  if (simulation_->TakeDrop()) {
    Close(client);
    return;
  }
  const int delay_ms = simulation_->response_delay_ms();
  if (delay_ms > 0) {
    client->pending = true;
    client->due = Clock::now() + std::chrono::milliseconds(delay_ms);
    return;
  }
  if (!Answer(client)) Close(client);
}

bool ModbusSlave::Answer(Client* client) {
  client->pending = false;
  modbus_t* ctx = client->ctx;
  if (!client->serial) modbus_set_socket(ctx, client->fd);
  const std::uint8_t* req = client->request.data();
  const int header_length = modbus_get_header_length(ctx);
  const std::uint8_t* pdu = req + header_length;
  const int function = pdu[0];
  const int exception = simulation_->read_exception_code();
  if (exception != 0 && IsRead(function)) {
    return modbus_reply_exception(ctx, req, static_cast<unsigned>(exception)) >= 0;
  }
  auto& holding = simulation_->holding_registers();
  const int size = static_cast<int>(holding.size());
  int first = 0;
  int count = 0;
  bool wrote = false;
  // Copies `n` registers of the request starting at byte `values` into the image, if the
  // request is well formed (otherwise modbus_reply answers it with an exception).
  auto store = [&](int address, int n, int byte_count, int values) {
    if (n < 1 || n > MODBUS_MAX_WRITE_REGISTERS || address + n > size || byte_count != 2 * n ||
        client->request_length < header_length + values + 2 * n) {
      return;
    }
    for (int i = 0; i < n; ++i) {
      holding[static_cast<std::size_t>(address) + static_cast<std::size_t>(i)] =
          static_cast<std::uint16_t>(Word(pdu + values + 2 * std::ptrdiff_t{i}));
    }
    first = address;
    count = n;
    wrote = true;
  };
  // Writes go into the image and through the PLC logic before the reply, so that a master that
  // got the reply sees their effect (lockstep steps included).
  if (function == MODBUS_FC_WRITE_SINGLE_REGISTER) {
    store(Word(pdu + 1), 1, 2, 3);
  } else if (function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS) {
    store(Word(pdu + 1), Word(pdu + 3), pdu[5], 6);
  } else if (function == MODBUS_FC_WRITE_AND_READ_REGISTERS) {
    store(Word(pdu + 5), Word(pdu + 7), pdu[9], 10);
  } else if (function == MODBUS_FC_MASK_WRITE_REGISTER) {
    const int address = Word(pdu + 1);
    if (address < size) {
      const int and_mask = Word(pdu + 3);
      const int or_mask = Word(pdu + 5);
      holding[static_cast<std::size_t>(address)] = static_cast<std::uint16_t>(
          (holding[static_cast<std::size_t>(address)] & and_mask) | (or_mask & ~and_mask & 0xFFFF));
      first = address;
      count = 1;
      wrote = true;
    }
  }
  if (wrote) simulation_->OnHoldingWrite(first, count);
  const int rc = modbus_reply(ctx, req, client->request_length, &mapping_);
  // modbus_reply stored the raw written values again: put back what the PLC made of them.
  if (wrote) simulation_->PublishHoldings();
  return rc >= 0;
}

void ModbusSlave::StepClock(Clock::time_point now) {
  if (simulation_->lockstep()) return;
  const std::chrono::duration<double> period(simulation_->config().plant_step_s /
                                             clock_.time_scale);
  // Catch up short lags (a busy machine delays the loop by milliseconds, which at 600 x real
  // time is several plant steps): skipping them would make plant time run slower than
  // time_scale x wall time, and a master that counts samples (as canalidd does) would see a
  // plant that changes too little per sample.  Only a lag above one wall second is skipped.
  const auto max_steps = static_cast<int>(std::max(1.0, std::ceil(1.0 / period.count())));
  int done = 0;
  while (now >= start_ + (clock_steps_ + 1) * period) {
    if (done == max_steps) {
      ++overruns_;
      simulation_->set_overruns(overruns_);
      start_ = now - std::chrono::duration_cast<Clock::duration>(clock_steps_ * period);
      break;
    }
    simulation_->Step();
    ++clock_steps_;
    ++done;
  }
}

void ModbusSlave::Run(const volatile std::sig_atomic_t* stop, const sigset_t* wait_mask) {
  while (*stop == 0) {
    const Clock::time_point now = Clock::now();
    StepClock(now);
    Clock::time_point wake = now + std::chrono::seconds(1);
    if (!simulation_->lockstep()) {
      const std::chrono::duration<double> period(simulation_->config().plant_step_s /
                                                 clock_.time_scale);
      wake = std::min(
          wake, start_ + std::chrono::duration_cast<Clock::duration>((clock_steps_ + 1) * period));
    }
    fd_set readable;
    FD_ZERO(&readable);
    int max_fd = -1;
    if (listen_fd_ >= 0) {
      FD_SET(listen_fd_, &readable);
      max_fd = listen_fd_;
    }
    for (const Client& c : clients_) {
      if (c.pending) {
        wake = std::min(wake, c.due);
      } else {
        FD_SET(c.fd, &readable);
        max_fd = std::max(max_fd, c.fd);
      }
    }
    const timespec timeout = ToTimespec(wake - Clock::now());
    const int n = pselect(max_fd + 1, &readable, nullptr, nullptr, &timeout, wait_mask);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("select failed: ") + core::ErrnoText(errno));
    }
    // Iterate by index: Accept appends to clients_.
    const std::size_t existing = clients_.size();
    if (n > 0 && listen_fd_ >= 0 && FD_ISSET(listen_fd_, &readable)) Accept();
    for (std::size_t i = 0; i < existing; ++i) {
      Client& c = clients_[i];
      if (c.fd < 0) continue;
      if (c.pending) {
        if (Clock::now() >= c.due && !Answer(&c)) Close(&c);
      } else if (n > 0 && FD_ISSET(c.fd, &readable)) {
        Receive(&c);
      }
    }
    std::erase_if(clients_, [](const Client& c) { return c.fd < 0; });
  }
}

}  // namespace canalid::sim::plc
