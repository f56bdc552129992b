// Lines of a program file for the streaming readers (APT, SINUMERIK). Internal to vcut::io.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <istream>
#include <string>
#include <vector>

namespace vcut::io::detail {

inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;

// Lines from a stream in 64 KiB reads, each at most kMaxLineBytes (1 MiB) (a binary file with no line
// breaks cannot take all the memory).
class LineSource {
 public:
  explicit LineSource(std::istream& in) : in_(in), buffer_(std::size_t{1} << 16) {}
  enum Result { kLine, kEnd, kTooLong };
  // Lines in `bytes` more bytes, estimated from the first read (after the first next()).
  size_t estimate_lines(double bytes) const {
    if (first_bytes_ == 0 || !(bytes > 0.0)) return 0;
    return static_cast<size_t>(
        std::min(1e9, bytes * static_cast<double>(first_newlines_ + 1) / static_cast<double>(first_bytes_)));
  }
  Result next(std::string& line) {
    line.clear();
    bool any = false;
    while (true) {
      if (pos_ == end_) {
        if (eof_) return any ? kLine : kEnd;
        in_.read(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
        end_ = static_cast<size_t>(in_.gcount());
        pos_ = 0;
        if (reads_++ == 0) {
          first_bytes_ = end_;
          first_newlines_ = static_cast<size_t>(std::count(buffer_.data(), buffer_.data() + end_, '\n'));
        }
        if (!in_) eof_ = true;
        if (end_ == 0) return any ? kLine : kEnd;
      }
      const char* start = buffer_.data() + pos_;
      const auto* newline = static_cast<const char*>(std::memchr(start, '\n', end_ - pos_));
      const size_t n = newline ? static_cast<size_t>(newline - start) : end_ - pos_;
      if (line.size() + n > kMaxLineBytes) return kTooLong;
      line.append(start, n);
      any = true;
      pos_ += n;
      if (newline) {
        ++pos_;
        return kLine;
      }
    }
  }

 private:
  std::istream& in_;
  std::vector<char> buffer_;
  size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  size_t reads_ = 0, first_bytes_ = 0, first_newlines_ = 0;
};

}  // namespace vcut::io::detail
