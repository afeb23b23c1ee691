// Byte streams from the controller: a serial device (termios, raw 8N1, non-blocking) or a UDP port on
// which a companion-computer MAVLink router forwards the flight controller's traffic; and pseudo-terminals
// for the emulator and the tests. Opening throws std::runtime_error with a message a person can act on;
// reading never blocks (wait with waitReadable first).
// Thread-safety: one thread per stream.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace toposlam::firmware {

struct ReadResult {
  enum Kind { Data, Nothing, Closed } kind = Nothing;
  std::size_t size = 0;
  std::string error;  ///< for Closed: what happened (errno text, "hang-up")
};

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  virtual int fd() const = 0;
  virtual ReadResult read(std::span<std::uint8_t> into) = 0;
  /// Writes all of `bytes` (blocking briefly if needed); false on error.
  virtual bool write(std::span<const std::uint8_t> bytes) = 0;
  virtual std::string describe() const = 0;
};

/// Standard baud rates termios knows on Linux; 0 if `baud` is none of them.
bool baudSupported(int baud);
std::string supportedBauds();

/// Opens `path` raw 8N1 at `baud`. Errors: missing device, permission (dialout group), not a tty,
/// unsupported baud rate.
std::unique_ptr<ByteStream> openSerial(const std::string& path, int baud);
/// Binds a UDP socket on `address`:`port` (e.g. 127.0.0.1:14550, where mavlink-router sends).
std::unique_ptr<ByteStream> openUdp(const std::string& address, int port);
/// Wraps an already open descriptor (takes ownership), e.g. a pty master.
std::unique_ptr<ByteStream> adoptDescriptor(int fd, std::string description);

enum class WaitResult { Readable, Timeout, Error };
/// poll() for input or hang-up, up to timeout_ms.
WaitResult waitReadable(int fd, int timeout_ms);

/// A pseudo-terminal pair: the emulator writes the master, the bridge opens `slave_path`. The slave end
/// stays open here too, so the master never sees EIO before the bridge opens it.
struct PseudoTerminal {
  int master = -1;
  int slave = -1;
  std::string slave_path;
  PseudoTerminal() = default;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;
  PseudoTerminal(PseudoTerminal&& other) noexcept;
  PseudoTerminal& operator=(PseudoTerminal&&) = delete;
  ~PseudoTerminal();
  /// Closes the master side: the reader sees a hang-up.
  void closeMaster();
};
/// Opens a raw pseudo-terminal; throws std::runtime_error.
PseudoTerminal openPseudoTerminal();

}  // namespace toposlam::firmware
