// termios serial devices, UDP sockets and pseudo-terminals (see serial_port.hpp).
#include "toposlam/firmware/serial_port.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace toposlam::firmware {

namespace {

struct BaudRate {
  int baud;
  speed_t speed;
};
constexpr BaudRate kBauds[] = {
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400},   {460800, B460800},   {500000, B500000},   {576000, B576000},   {921600, B921600},
    {1000000, B1000000}, {1500000, B1500000}, {2000000, B2000000}, {3000000, B3000000}, {4000000, B4000000},
};

std::string errnoText(int e) { return std::strerror(e); }

class FdStream final : public ByteStream {
 public:
  FdStream(int fd, std::string description, bool datagram)
      : fd_(fd), description_(std::move(description)), datagram_(datagram) {}
  ~FdStream() override {
    if (fd_ >= 0) ::close(fd_);
  }
  int fd() const override { return fd_; }
  ReadResult read(std::span<std::uint8_t> into) override {
    const ssize_t n = datagram_ ? ::recv(fd_, into.data(), into.size(), MSG_DONTWAIT) : ::read(fd_, into.data(), into.size());
    if (n > 0) return {ReadResult::Data, static_cast<std::size_t>(n), {}};
    if (n == 0) return datagram_ ? ReadResult{} : ReadResult{ReadResult::Closed, 0, "end of file (hang-up)"};
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return {};
    return {ReadResult::Closed, 0, errnoText(errno)};
  }
  bool write(std::span<const std::uint8_t> bytes) override {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
      } else if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
        pollfd p{fd_, POLLOUT, 0};
        if (::poll(&p, 1, 100) < 0 && errno != EINTR) return false;
      } else {
        return false;
      }
    }
    return true;
  }
  std::string describe() const override { return description_; }

 private:
  int fd_;
  std::string description_;
  bool datagram_;
};

void makeRaw(int fd, speed_t speed) {
  termios t{};
  if (tcgetattr(fd, &t) != 0) throw std::runtime_error("tcgetattr: " + errnoText(errno));
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
  // VMIN 1 with O_NONBLOCK: no data gives EAGAIN, so a 0 from read() can only mean a hang-up (with
  // VMIN 0 a tty returns 0 for "nothing yet" as well).
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (cfsetispeed(&t, speed) != 0 || cfsetospeed(&t, speed) != 0) throw std::runtime_error("cfsetspeed failed");
  if (tcsetattr(fd, TCSANOW, &t) != 0) throw std::runtime_error("tcsetattr: " + errnoText(errno));
}

}  // namespace

bool baudSupported(int baud) {
  for (const BaudRate& b : kBauds)
    if (b.baud == baud) return true;
  return false;
}

std::string supportedBauds() {
  std::string out;
  for (const BaudRate& b : kBauds) out += (out.empty() ? "" : ", ") + std::to_string(b.baud);
  return out;
}

std::unique_ptr<ByteStream> openSerial(const std::string& path, int baud) {
  speed_t speed = 0;
  bool found = false;
  for (const BaudRate& b : kBauds)
    if (b.baud == baud) {
      speed = b.speed;
      found = true;
    }
  if (!found)
    throw std::runtime_error("baud rate " + std::to_string(baud) + " is not a standard rate; use one of " +
                             supportedBauds() + " (the controller firmware's UART setting)");
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    std::string hint;
    if (e == ENOENT) hint = " (is the controller plugged in and powered? see ls /dev/serial/by-id/)";
    if (e == EACCES) hint = " (add the user to the 'dialout' group, or run as a member of it)";
    if (e == EBUSY) hint = " (another program holds it: fuser " + path + ")";
    throw std::runtime_error("cannot open serial device '" + path + "': " + errnoText(e) + hint);
  }
  if (!isatty(fd)) {
    ::close(fd);
    throw std::runtime_error("'" + path + "' is not a serial device (not a tty)");
  }
  try {
    makeRaw(fd, speed);
  } catch (const std::exception& e) {
    ::close(fd);
    throw std::runtime_error("cannot configure serial device '" + path + "' at " + std::to_string(baud) +
                             " baud: " + e.what());
  }
  tcflush(fd, TCIFLUSH);  // bytes from before we configured the line are at the wrong rate
  return std::make_unique<FdStream>(fd, path + " @ " + std::to_string(baud) + " baud", false);
}

std::unique_ptr<ByteStream> openUdp(const std::string& address, int port) {
  if (port <= 0 || port > 65535) throw std::runtime_error("UDP port " + std::to_string(port) + " is not in 1..65535");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw std::runtime_error("'" + address + "' is not an IPv4 address (e.g. 127.0.0.1)");
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) throw std::runtime_error("cannot create a UDP socket: " + errnoText(errno));
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int e = errno;
    ::close(fd);
    throw std::runtime_error("cannot bind UDP " + address + ":" + std::to_string(port) + ": " + errnoText(e) +
                             (e == EADDRINUSE ? " (another program listens there: ss -ulpn)" : ""));
  }
  return std::make_unique<FdStream>(fd, "udp:" + address + ":" + std::to_string(port), true);
}

std::unique_ptr<ByteStream> adoptDescriptor(int fd, std::string description) {
  return std::make_unique<FdStream>(fd, std::move(description), false);
}

WaitResult waitReadable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r < 0) return errno == EINTR ? WaitResult::Timeout : WaitResult::Error;
  if (r == 0) return WaitResult::Timeout;
  // POLLHUP/POLLERR: let read() report what happened.
  return WaitResult::Readable;
}

PseudoTerminal::PseudoTerminal(PseudoTerminal&& o) noexcept
    : master(std::exchange(o.master, -1)), slave(std::exchange(o.slave, -1)), slave_path(std::move(o.slave_path)) {}

PseudoTerminal::~PseudoTerminal() {
  closeMaster();
  if (slave >= 0) ::close(slave);
}

void PseudoTerminal::closeMaster() {
  if (master >= 0) ::close(master);
  master = -1;
}

PseudoTerminal openPseudoTerminal() {
  PseudoTerminal p;
  char name[256] = {};
  termios t{};
  cfmakeraw(&t);
  if (::openpty(&p.master, &p.slave, name, &t, nullptr) != 0)
    throw std::runtime_error("openpty failed: " + errnoText(errno));
  fcntl(p.master, F_SETFD, FD_CLOEXEC);
  fcntl(p.slave, F_SETFD, FD_CLOEXEC);
  p.slave_path = name;
  return p;
}

}  // namespace toposlam::firmware
