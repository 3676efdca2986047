#include "drivers/modbus/results_server.h"

#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <stdexcept>
#include <vector>

namespace canalid::drivers {
namespace {

int Word(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }

bool IsWrite(int function) {
  return function == MODBUS_FC_WRITE_SINGLE_COIL || function == MODBUS_FC_WRITE_SINGLE_REGISTER ||
         function == MODBUS_FC_WRITE_MULTIPLE_COILS ||
         function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS ||
         function == MODBUS_FC_MASK_WRITE_REGISTER ||
         function == MODBUS_FC_WRITE_AND_READ_REGISTERS;
}

double NowS() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

int BoundPort(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  if (getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) return 0;
  if (address.ss_family == AF_INET) {
    return ntohs(reinterpret_cast<const sockaddr_in*>(&address)->sin_port);
  }
  if (address.ss_family == AF_INET6) {
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&address)->sin6_port);
  }
  return 0;
}

}  // namespace

/// What the serving thread owns: the libmodbus context, the sockets, the reply buffer.
struct ResultsServer::Connections {
  modbus_t* ctx = nullptr;
  int listen_fd = -1;
  std::vector<int> clients;
  std::vector<std::uint16_t> words;  ///< the registers a reply reads (filled per request)
  modbus_mapping_t mapping{};
  std::vector<std::uint8_t> request = std::vector<std::uint8_t>(MODBUS_TCP_MAX_ADU_LENGTH);

  ~Connections() {
    for (const int fd : clients) close(fd);
    if (listen_fd >= 0) close(listen_fd);
    if (ctx != nullptr) modbus_free(ctx);
  }
};

ResultsServer::ResultsServer(core::ResultsImage image, ResultsServerOptions options)
    : image_(std::move(image)),
      options_(std::move(options)),
      connections_(std::make_unique<Connections>()) {
  const std::string where = options_.host + ":" + options_.port;
  Connections& c = *connections_;
  c.ctx = modbus_new_tcp_pi(options_.host.c_str(), options_.port.c_str());
  if (c.ctx == nullptr) {
    throw std::runtime_error("results map: cannot create a Modbus TCP context for " + where + ": " +
                             modbus_strerror(errno));
  }
  modbus_set_byte_timeout(c.ctx, 0, 100000);
  c.listen_fd = modbus_tcp_pi_listen(c.ctx, 64);
  if (c.listen_fd < 0) {
    throw std::runtime_error("results map: cannot listen on " + where + ": " +
                             modbus_strerror(errno));
  }
  port_ = BoundPort(c.listen_fd);
  c.words.assign(static_cast<std::size_t>(image_.size()), 0);
  c.mapping.nb_registers = image_.size();
  c.mapping.tab_registers = c.words.data();
  c.mapping.nb_input_registers = image_.size();
  c.mapping.tab_input_registers = c.words.data();
  stop_fd_ = eventfd(0, EFD_CLOEXEC);
  if (stop_fd_ < 0) throw std::runtime_error("results map: cannot create an eventfd");
  thread_ = std::thread([this] { Serve(); });
}

ResultsServer::~ResultsServer() {
  const std::uint64_t one = 1;
  if (write(stop_fd_, &one, sizeof(one)) < 0) {
    // Cannot happen for an eventfd below its maximum; the join below would then wait for ever,
    // so close the listening socket instead to end poll() with an error.
    shutdown(connections_->listen_fd, SHUT_RDWR);
  }
  if (thread_.joinable()) thread_.join();
  close(stop_fd_);
}

ResultsServerCounters ResultsServer::counters() const {
  return {requests_.load(),        refused_writes_.load(),  clients_accepted_.load(),
          clients_refused_.load(), clients_dropped_.load(), clients_connected_.load()};
}

void ResultsServer::Serve() {
  Connections& c = *connections_;
  std::vector<pollfd> fds;
  const int header = modbus_get_header_length(c.ctx);
  // Answers one request of `fd`; false when the connection must be closed.
  auto answer = [&](int fd) {
    modbus_set_socket(c.ctx, fd);
    const int length = modbus_receive(c.ctx, c.request.data());
    if (length < 0) {
      if (errno != ECONNRESET) clients_dropped_.fetch_add(1);
      return false;
    }
    if (length == 0) return true;  // not for us (libmodbus filtered it)
    const std::uint8_t* pdu = c.request.data() + header;
    const int function = pdu[0];
    requests_.fetch_add(1);
    if (IsWrite(function)) {
      refused_writes_.fetch_add(1);
      return modbus_reply_exception(c.ctx, c.request.data(), MODBUS_EXCEPTION_ILLEGAL_FUNCTION) >=
             0;
    }
    if ((function == MODBUS_FC_READ_HOLDING_REGISTERS ||
         function == MODBUS_FC_READ_INPUT_REGISTERS) &&
        length >= header + 5) {
      const int first = Word(pdu + 1);
      const int count = Word(pdu + 3);
      // Otherwise modbus_reply answers with the exception the request deserves.
      if (count >= 1 && count <= MODBUS_MAX_READ_REGISTERS && first + count <= image_.size()) {
        const std::lock_guard<std::mutex> lock(mutex_);
        image_.Read(
            NowS(), first,
            std::span<std::uint16_t>(c.words.data() + first, static_cast<std::size_t>(count)));
      }
    }
    if (modbus_reply(c.ctx, c.request.data(), length, &c.mapping) < 0) {
      clients_dropped_.fetch_add(1);
      return false;
    }
    return true;
  };
  for (;;) {
    fds.clear();
    fds.push_back({stop_fd_, POLLIN, 0});
    fds.push_back({c.listen_fd, POLLIN, 0});
    for (const int fd : c.clients) fds.push_back({fd, POLLIN, 0});
    if (poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      return;  // cannot wait any more: the map stops answering (its clients time out)
    }
    if (fds[0].revents != 0) return;
    for (std::size_t i = 2; i < fds.size(); ++i) {
      if (fds[i].revents == 0) continue;
      if ((fds[i].revents & POLLIN) == 0 || !answer(fds[i].fd)) {
        close(fds[i].fd);
        c.clients.erase(std::find(c.clients.begin(), c.clients.end(), fds[i].fd));
        clients_connected_.store(static_cast<std::int64_t>(c.clients.size()));
      }
    }
    if ((fds[1].revents & POLLIN) != 0) {
      const int fd = accept4(c.listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;  // the peer went away before we accepted
      // libmodbus waits on the socket with select(): a descriptor past FD_SETSIZE cannot be served.
      if (fd >= FD_SETSIZE || static_cast<int>(c.clients.size()) >= options_.max_clients) {
        close(fd);
        clients_refused_.fetch_add(1);
        continue;
      }
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      const timeval send_timeout{1, 0};
      setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &send_timeout, sizeof(send_timeout));
      c.clients.push_back(fd);
      clients_accepted_.fetch_add(1);
      clients_connected_.store(static_cast<std::int64_t>(c.clients.size()));
    }
  }
}

}  // namespace canalid::drivers
