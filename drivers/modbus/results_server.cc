#include "drivers/modbus/results_server.h"

#include <modbus/modbus.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/system/errno_text.h"

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

// The wall clock, for the ages a reply shows.
double WallNowS() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// The monotonic clock, for the connections' deadlines (a stepped wall clock moves none of them).
double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Frames answered per connection before the others get their turn.
constexpr int kFramesPerTurn = 16;
// How long accepting pauses when the process is out of descriptors or memory.
constexpr double kAcceptPauseS = 0.1;

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

std::string ResultsListenProblem(const std::string& host, const std::string& port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_ADDRCONFIG;  // as modbus_tcp_pi_listen
  addrinfo* found = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &found); rc != 0) {
    return gai_strerror(rc);
  }
  std::string problem = "no address";
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      problem = core::ErrnoText(errno);
      continue;
    }
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));  // as modbus_tcp_pi_listen
    const bool bound = bind(fd, a->ai_addr, a->ai_addrlen) == 0 && listen(fd, 1) == 0;
    if (!bound) problem = core::ErrnoText(errno);
    close(fd);
    if (bound) {
      problem.clear();
      break;
    }
  }
  freeaddrinfo(found);
  return problem;
}

/// One master's connection: the frame being received.
struct ResultsServer::Client {
  int fd = -1;
  std::array<std::uint8_t, MODBUS_TCP_MAX_ADU_LENGTH> frame{};
  int have = 0;               ///< bytes of the current frame received
  double frame_start_s = 0;   ///< when its first byte came
  double last_request_s = 0;  ///< the last whole request (or the connection's start)
};

/// What the serving thread owns: the libmodbus context, the sockets, the reply buffer.
struct ResultsServer::Connections {
  modbus_t* ctx = nullptr;
  int listen_fd = -1;
  std::vector<Client> clients;
  std::vector<std::uint16_t> words;  ///< the registers a reply reads (filled per request)
  modbus_mapping_t mapping{};

  ~Connections() {
    for (const Client& c : clients) close(c.fd);
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
  if (stop_fd_ < 0) {
    throw std::runtime_error("results map: cannot create an eventfd: " + core::ErrnoText(errno));
  }
  c.clients.reserve(static_cast<std::size_t>(options_.max_clients));
  thread_ = std::thread([this] { Serve(); });
}

ResultsServer::~ResultsServer() {
  stop_.store(true);
  const std::uint64_t one = 1;
  // Wakes poll() at once; were the write to fail, the loop sees stop_ within its 1 s wait.
  if (write(stop_fd_, &one, sizeof(one)) < 0) {
    // nothing more to do: see above
  }
  if (thread_.joinable()) thread_.join();
  close(stop_fd_);
}

ResultsServerCounters ResultsServer::counters() const {
  return {requests_.load(),        refused_writes_.load(),  clients_accepted_.load(),
          clients_refused_.load(), clients_dropped_.load(), clients_connected_.load()};
}

bool ResultsServer::Answer(Client& client) {
  Connections& c = *connections_;
  modbus_set_socket(c.ctx, client.fd);
  const std::uint8_t* req = client.frame.data();
  const int function = req[7];
  // A function code with the exception bit cannot be answered (its exception would read as a
  // reply of function code - 0x80): the frame is malformed.
  if (function >= 0x80) return false;
  requests_.fetch_add(1);
  auto exception = [&](unsigned code) { return modbus_reply_exception(c.ctx, req, code) >= 0; };
  if (IsWrite(function)) {
    refused_writes_.fetch_add(1);
    return exception(MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  }
  if (function != MODBUS_FC_READ_HOLDING_REGISTERS && function != MODBUS_FC_READ_INPUT_REGISTERS) {
    return exception(MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  }
  if (client.have != 12) return exception(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  const int first = Word(req + 8);
  const int count = Word(req + 10);
  // Checked here, not left to modbus_reply: its own exception path sleeps the response timeout
  // and flushes the socket (pipelined requests lost).  Only valid reads reach modbus_reply.
  if (count < 1 || count > MODBUS_MAX_READ_REGISTERS) {
    return exception(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  }
  if (first + count > image_.size()) return exception(MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    image_.Read(WallNowS(), first,
                std::span<std::uint16_t>(c.words.data() + first, static_cast<std::size_t>(count)));
  }
  // A reply that does not fit the socket's buffer at once fails (non-blocking): dropped.
  return modbus_reply(c.ctx, req, client.have, &c.mapping) >= 0;
}

bool ResultsServer::Receive(Client& client, double now_s) {
  constexpr int kHeader = 7;  // MBAP: transaction, protocol, length, unit
  for (int answered = 0; answered < kFramesPerTurn;) {
    int need = kHeader;
    if (client.have >= kHeader) {
      const int length = Word(client.frame.data() + 4);  // unit id and PDU
      if (Word(client.frame.data() + 2) != 0 || length < 2 ||
          6 + length > MODBUS_TCP_MAX_ADU_LENGTH) {
        clients_dropped_.fetch_add(1);
        return false;
      }
      need = 6 + length;
    }
    if (client.have == need) {  // a whole frame: answered, then the next one
      client.last_request_s = now_s;
      const bool ok = Answer(client);
      client.have = 0;
      ++answered;
      if (!ok) {
        clients_dropped_.fetch_add(1);
        return false;
      }
      continue;
    }
    const ssize_t n = recv(client.fd, client.frame.data() + client.have,
                           static_cast<std::size_t>(need - client.have), 0);
    if (n == 0) return false;  // the master closed the connection
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return true;
      return false;  // reset by the peer
    }
    if (client.have == 0) client.frame_start_s = now_s;
    client.have += static_cast<int>(n);
  }
  return true;  // the others' turn; poll() reports what is left at once
}

void ResultsServer::Serve() {
  Connections& c = *connections_;
  std::vector<pollfd> fds;
  double accept_paused_until = 0.0;
  while (!stop_.load()) {
    const double now = SteadyNowS();
    // Drop the connections past their deadline; wait at most until the next one (and 1 s).
    double wait_s = 1.0;
    std::erase_if(c.clients, [&](const Client& client) {
      const double deadline = client.have > 0 ? client.frame_start_s + options_.frame_timeout_s
                                              : client.last_request_s + options_.idle_timeout_s;
      if (now >= deadline) {
        close(client.fd);
        clients_dropped_.fetch_add(1);
        return true;
      }
      wait_s = std::min(wait_s, deadline - now);
      return false;
    });
    clients_connected_.store(static_cast<std::int64_t>(c.clients.size()));
    fds.clear();
    fds.push_back({stop_fd_, POLLIN, 0});
    const bool accepting = now >= accept_paused_until;
    if (!accepting) wait_s = std::min(wait_s, accept_paused_until - now);
    fds.push_back({c.listen_fd, static_cast<short>(accepting ? POLLIN : 0), 0});
    for (const Client& client : c.clients) fds.push_back({client.fd, POLLIN, 0});
    const int wait_ms = static_cast<int>(std::ceil(wait_s * 1000.0));
    if (poll(fds.data(), fds.size(), wait_ms) < 0) {
      if (errno == EINTR) continue;
      return;  // cannot wait any more: the map stops answering (its masters time out)
    }
    if (fds[0].revents != 0) return;
    const double received = SteadyNowS();
    for (std::size_t i = 2; i < fds.size(); ++i) {
      if (fds[i].revents == 0) continue;
      Client& client = c.clients[i - 2];
      if (!Receive(client, received)) {
        close(client.fd);
        client.fd = -1;
      }
    }
    std::erase_if(c.clients, [](const Client& client) { return client.fd < 0; });
    if ((fds[1].revents & POLLIN) != 0) {
      const int fd = accept4(c.listen_fd, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
      if (fd < 0) {
        // Out of descriptors or memory: the connection stays queued and the socket readable, so
        // accepting pauses instead of spinning.  (Otherwise the peer went away first.)
        if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
          accept_paused_until = received + kAcceptPauseS;
        }
        continue;
      }
      if (static_cast<int>(c.clients.size()) >= options_.max_clients) {
        close(fd);
        clients_refused_.fetch_add(1);
        continue;
      }
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      Client client;
      client.fd = fd;
      client.last_request_s = received;
      c.clients.push_back(client);
      clients_accepted_.fetch_add(1);
    }
    clients_connected_.store(static_cast<std::int64_t>(c.clients.size()));
  }
}

}  // namespace canalid::drivers
