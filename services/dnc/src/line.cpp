// The termios tty (docs/dnc.md "The line").
#include "cell/dnc/line.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

namespace cell::dnc {
namespace {

speed_t Speed(int baud) {
  switch (baud) {
    case 110:
      return B110;
    case 150:
      return B150;
    case 300:
      return B300;
    case 600:
      return B600;
    case 1200:
      return B1200;
    case 2400:
      return B2400;
    case 4800:
      return B4800;
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    default:
      return B0;
  }
}

int Poll(int fd, short events, std::chrono::microseconds wait) {
  pollfd p{fd, events, 0};
  timespec ts{static_cast<time_t>(wait.count() / 1000000), static_cast<long>(wait.count() % 1000000) * 1000};
  int n = ::ppoll(&p, 1, &ts, nullptr);
  if (n <= 0) return 0;
  return p.revents;
}

void Configure(const Serial& s, termios& t) {
  ::cfmakeraw(&t);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  t.c_cflag |= CREAD | CLOCAL | HUPCL;
  const Format& f = s.format;
  bool uart_parity = f.data_bits == 8 && f.parity != Parity::kNone && f.code == Code::kIso;
  bool seven = f.data_bits == 7 && f.parity == Parity::kNone && f.code == Code::kIso;
  t.c_cflag |= seven ? CS7 : CS8;
  if (uart_parity) t.c_cflag |= PARENB | (f.parity == Parity::kOdd ? PARODD : 0);
  if (s.stop_bits == 2) t.c_cflag |= CSTOPB;
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY | ISTRIP | IGNPAR | BRKINT);
  t.c_iflag |= INPCK | PARMRK | IGNBRK;
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  ::cfsetispeed(&t, Speed(s.baud));
  ::cfsetospeed(&t, Speed(s.baud));
}

}  // namespace

size_t Unmarker::Take(std::span<uint8_t> bytes, std::optional<uint8_t>& damaged) {
  size_t out = 0;
  for (uint8_t b : bytes) {
    if (state_ == 2) {
      state_ = 0;
      damaged = b;
      return out;
    }
    if (state_ == 1) {
      state_ = b == 0xFF ? 0 : 2;  // \377 \377 is a data 0xFF; \377 \0 marks the next byte
      if (b == 0xFF) bytes[out++] = b;
      continue;
    }
    if (b == 0xFF) {
      state_ = 1;
      continue;
    }
    bytes[out++] = b;
  }
  return out;
}

std::unique_ptr<TtyPort> TtyPort::Open(const Serial& s) {
  if (Speed(s.baud) == B0) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("device {}: baud {} is not a termios rate", s.device, s.baud));
  }
  int fd = ::open(s.device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    int err = errno;
    if (err == ENOENT || err == ENXIO || err == ENODEV) {
      throw Error(Errc::kNotFound, fmt::format("device {}: does not exist", s.device));
    }
    if (err == EBUSY) throw Error(Errc::kUnavailable, fmt::format("device {}: busy", s.device));
    if (err == EACCES || err == EPERM) {
      throw Error(Errc::kPermissionDenied,
                  fmt::format("device {}: permission denied (the dialout group?)", s.device));
    }
    throw Error(Errc::kIo, fmt::format("device {}: {}", s.device, std::strerror(err)));
  }
  std::unique_ptr<TtyPort> port(new TtyPort(s.device, fd));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    throw Error(Errc::kUnavailable, fmt::format("device {}: busy (held by another process)", s.device));
  }
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("device {}: not a serial line ({})", s.device, std::strerror(errno)));
  }
  Configure(s, t);
  if (::tcsetattr(fd, TCSANOW, &t) != 0) {
    throw Error(Errc::kIo, fmt::format("device {}: cannot set the line: {}", s.device, std::strerror(errno)));
  }
  ::ioctl(fd, TIOCEXCL);
  ::tcflush(fd, TCIOFLUSH);
  return port;
}

TtyPort::~TtyPort() {
  if (fd_ >= 0) ::close(fd_);
}

void TtyPort::Fail(std::string_view what, int err) const {
  if (err == EIO || err == ENXIO || err == 0) throw Error(Errc::kUnavailable, "hang-up");
  throw Error(Errc::kIo, fmt::format("{}: {}", what, std::strerror(err)));
}

size_t TtyPort::Read(std::span<uint8_t> out, std::chrono::microseconds wait) {
  if (damaged_) {
    uint8_t b = *damaged_;
    damaged_.reset();
    throw Error(Errc::kInvalidArgument, fmt::format("parity or framing error (0x{:02X})", b));
  }
  int ev = Poll(fd_, POLLIN, wait);
  if (ev == 0) return 0;
  ssize_t n = ::read(fd_, out.data(), out.size());
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
  if (n < 0) Fail("read", errno);
  if (n == 0) Fail("read", 0);  // end of file on a tty: the other end hung up
  return unmark_.Take(out.first(static_cast<size_t>(n)), damaged_);
}

size_t TtyPort::Write(std::span<const uint8_t> bytes, std::chrono::microseconds wait) {
  ssize_t n = ::write(fd_, bytes.data(), bytes.size());
  if (n >= 0) return static_cast<size_t>(n);
  if (errno != EAGAIN && errno != EINTR) Fail("write", errno);
  int ev = Poll(fd_, POLLOUT, wait);
  if (ev & (POLLHUP | POLLERR)) Fail("write", EIO);
  return 0;
}

bool TtyPort::ClearToSend() {
  int bits = 0;
  if (::ioctl(fd_, TIOCMGET, &bits) != 0) return true;  // a pseudo-terminal has no modem lines
  return (bits & TIOCM_CTS) != 0;
}

void TtyPort::RequestToSend(bool on) {
  int bit = TIOCM_RTS;
  ::ioctl(fd_, on ? TIOCMBIS : TIOCMBIC, &bit);
}

void TtyPort::Drain() {
  if (::tcdrain(fd_) != 0 && errno != EINTR) Fail("drain", errno);
}

double LineRate(const Serial& s) {
  const Format& f = s.format;
  int data = f.data_bits == 7 && f.parity != Parity::kNone && f.code == Code::kIso ? 8 : f.data_bits;
  if (f.code == Code::kEia) data = 8;
  int uart_parity = f.data_bits == 8 && f.parity != Parity::kNone && f.code == Code::kIso ? 1 : 0;
  return s.baud / static_cast<double>(1 + data + uart_parity + s.stop_bits);
}

}  // namespace cell::dnc
