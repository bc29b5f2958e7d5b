#pragma once
// How much of a TCP connection's output its peer has taken (issue 44: the viewer server cuts
// clients that read their response too slowly). Its own file: the kernel's struct tcp_info
// (linux/tcp.h) clashes with glibc's shorter one (netinet/tcp.h, included by httplib.h).
#include <cstdint>
#include <optional>

namespace semap::app {

/// Bytes sent on socket `fd` that the peer has acknowledged (TCP_INFO tcpi_bytes_acked, Linux
/// 4.1+); nullopt when the kernel does not say. Thread-safe.
std::optional<uint64_t> tcp_bytes_acked(int fd);

}  // namespace semap::app
