// A plain HTTP/1.1 client from a socket, and gRPC-Web's framing, for the tests that speak
// gRPC-Web to the server as a browser (or a hostile client) would.
#ifndef SPORTSIM_TESTS_SERVER_WEB_CLIENT_H_
#define SPORTSIM_TESTS_SERVER_WEB_CLIENT_H_

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"

namespace sportsim::server {

struct HttpResponse {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;                            // de-chunked
  std::string header(const std::string& name) const {
    const auto it = headers.find(name);
    return it == headers.end() ? "" : it->second;
  }
};

/// One HTTP/1.1 connection to 127.0.0.1:port, from 127.0.0.1 or another loopback address
/// (`from`: 127.0.0.from, so that tests can be many clients), reads timing out after
/// `timeout_s`.
class Http {
 public:
  explicit Http(int port, int from = 1, double timeout_s = 20) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (from != 1) {
      sockaddr_in src{};
      src.sin_family = AF_INET;
      src.sin_addr.s_addr = htonl(INADDR_LOOPBACK - 1 + static_cast<uint32_t>(from));
      (void)::bind(fd_, reinterpret_cast<sockaddr*>(&src), sizeof(src));
    }
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const auto us = static_cast<int64_t>(timeout_s * 1e6);
    timeval tv{.tv_sec = us / 1000000, .tv_usec = us % 1000000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
    ok_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  }
  Http(const Http&) = delete;
  Http& operator=(const Http&) = delete;
  ~Http() { Close(); }
  bool ok() const { return ok_; }
  int fd() const { return fd_; }
  void Close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  bool Send(const std::string& s) {
    size_t off = 0;
    while (off < s.size()) {
      const ssize_t n = ::send(fd_, s.data() + off, s.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return false;
      off += static_cast<size_t>(n);
    }
    return true;
  }
  // Reads the status line and headers.
  bool ReadHead(HttpResponse* r) {
    while (buf_.find("\r\n\r\n") == std::string::npos) {
      if (!Fill()) return false;
    }
    const size_t end = buf_.find("\r\n\r\n");
    const std::vector<std::string> lines = absl::StrSplit(buf_.substr(0, end), "\r\n");
    buf_.erase(0, end + 4);
    const std::vector<std::string> first = absl::StrSplit(lines[0], ' ');
    if (first.size() < 2 || !absl::SimpleAtoi(first[1], &r->status)) return false;
    for (size_t i = 1; i < lines.size(); ++i) {
      const size_t colon = lines[i].find(':');
      if (colon == std::string::npos) continue;
      r->headers[absl::AsciiStrToLower(lines[i].substr(0, colon))] =
          std::string(absl::StripAsciiWhitespace(lines[i].substr(colon + 1)));
    }
    chunked_ = absl::StrContains(r->header("transfer-encoding"), "chunked");
    remaining_ = -1;
    if (!chunked_ && r->headers.count("content-length")) {
      (void)absl::SimpleAtoi(r->header("content-length"), &remaining_);
    }
    return true;
  }
  // The next piece of the body (a chunk, or what the content length says); false at the end.
  bool ReadBodyPiece(std::string* out) {
    out->clear();
    if (chunked_) {
      while (buf_.find("\r\n") == std::string::npos) {
        if (!Fill()) return false;
      }
      const size_t eol = buf_.find("\r\n");
      char* end = nullptr;
      const std::string size = buf_.substr(0, eol);
      const int64_t n = std::strtoll(size.c_str(), &end, 16);
      if (size.empty() || end == size.c_str() || n < 0) return false;
      while (buf_.size() < eol + 2 + static_cast<size_t>(n) + 2) {
        if (!Fill()) return false;
      }
      *out = buf_.substr(eol + 2, static_cast<size_t>(n));
      buf_.erase(0, eol + 2 + static_cast<size_t>(n) + 2);
      return n > 0;
    }
    if (remaining_ == 0) return false;
    if (remaining_ > 0) {
      while (buf_.size() < static_cast<size_t>(remaining_)) {
        if (!Fill()) return false;
      }
      *out = buf_.substr(0, static_cast<size_t>(remaining_));
      buf_.erase(0, static_cast<size_t>(remaining_));
      remaining_ = 0;
      return true;
    }
    while (Fill()) {
    }
    *out = std::move(buf_);
    buf_.clear();
    remaining_ = 0;
    return !out->empty();
  }
  HttpResponse ReadAll() {
    HttpResponse r;
    if (!ReadHead(&r)) return r;
    std::string piece;
    while (ReadBodyPiece(&piece)) r.body += piece;
    return r;
  }

 private:
  bool Fill() {
    char b[16384];
    const ssize_t n = ::recv(fd_, b, sizeof(b), 0);
    if (n <= 0) return false;
    buf_.append(b, static_cast<size_t>(n));
    return true;
  }
  int fd_ = -1;
  bool ok_ = false;
  std::string buf_;
  bool chunked_ = false;
  int64_t remaining_ = -1;
};

inline std::string WebFrameBytes(uint8_t flag, const std::string& payload) {
  std::string f(5, '\0');
  f[0] = static_cast<char>(flag);
  const uint32_t n = static_cast<uint32_t>(payload.size());
  for (int i = 0; i < 4; ++i) f[static_cast<size_t>(1 + i)] = static_cast<char>(n >> (24 - 8 * i));
  return f + payload;
}

struct WebFrame {
  uint8_t flag = 0;
  std::string payload;
};

// Splits a binary gRPC-Web body into frames; false when it does not split evenly.
inline bool SplitFrames(const std::string& body, std::vector<WebFrame>* out) {
  size_t off = 0;
  while (off < body.size()) {
    if (body.size() - off < 5) return false;
    const auto byte = [&](size_t i) { return static_cast<uint32_t>(static_cast<uint8_t>(body[off + i])); };
    const uint32_t n = byte(1) << 24 | byte(2) << 16 | byte(3) << 8 | byte(4);
    if (body.size() - off - 5 < n) return false;
    out->push_back({static_cast<uint8_t>(body[off]), body.substr(off + 5, n)});
    off += 5 + n;
  }
  return true;
}

// A text body: base64, possibly several padded pieces one after another.
inline bool DecodeText(const std::string& text, std::string* out) {
  out->clear();
  size_t start = 0;
  while (start < text.size()) {
    size_t end = start;
    while (end < text.size() && text[end] != '=') ++end;
    while (end < text.size() && text[end] == '=') ++end;
    std::string piece;
    if (!absl::Base64Unescape(text.substr(start, end - start), &piece)) return false;
    *out += piece;
    start = end;
  }
  return true;
}

inline std::map<std::string, std::string> Trailers(const std::string& payload) {
  std::map<std::string, std::string> out;
  for (absl::string_view line : absl::StrSplit(payload, "\r\n", absl::SkipEmpty())) {
    const size_t colon = line.find(':');
    if (colon == absl::string_view::npos) continue;
    out[absl::AsciiStrToLower(line.substr(0, colon))] =
        std::string(absl::StripAsciiWhitespace(line.substr(colon + 1)));
  }
  return out;
}

struct WebCall {
  HttpResponse http;
  std::vector<std::string> messages;
  std::map<std::string, std::string> trailers;
  int grpc_status = -1;
  std::string grpc_message;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_TESTS_SERVER_WEB_CLIENT_H_
