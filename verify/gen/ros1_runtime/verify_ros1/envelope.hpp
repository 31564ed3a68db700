// verify_ros1/envelope.hpp: the record that travels out of band beside every message a generated node
// publishes (specs/codegen.md §6, "The wire"). The message itself is the port's ROS message on the
// port's topic; its record is on TOPIC/verify. Part of the runtime library that `verify gen ros1`
// copies into a generated project; usable on its own from hand-written nodes.
//
// A record is a std_msgs/UInt8MultiArray (an empty layout) whose data is, little-endian:
//   "VFY2"                          magic and version
//   u64 index                       the message's number on its topic, from its publisher (1, 2, ...)
//   u64 seq                         the writer job's number (1, 2, ...)
//   i64 release, start, finish      the writer job's release, start and completion (ns since the Unix epoch)
//   u64 event                       the activation event that released the job
//   u16 n, then n stamps            per chain through the port: u16 chain, u16 position,
//                                   i64 origin (the first task's read), i64 first (its first read)
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace verify_ros1 {

using Nanos = std::int64_t;

// A chain's provenance on a value (specs/timing.md §4): the read time of the first task's job whose
// data it carries, and that task's first read since the node started.
struct Stamp {
  std::uint16_t chain = 0;
  std::uint16_t position = 0;
  Nanos origin = 0;
  Nanos first = 0;
};

struct Envelope {
  std::uint64_t index = 0;
  std::uint64_t seq = 0;
  Nanos release = 0;
  Nanos start = 0;
  Nanos finish = 0;
  std::uint64_t event = 0;
  std::vector<Stamp> stamps;
};

namespace detail {

inline void put(std::vector<std::uint8_t>& out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) {
    out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
}

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool get(std::uint64_t& value, int bytes) {
    if (size_ - pos_ < static_cast<std::size_t>(bytes)) {
      return false;
    }
    value = 0;
    for (int i = 0; i < bytes; ++i) {
      value |= static_cast<std::uint64_t>(data_[pos_ + static_cast<std::size_t>(i)]) << (8 * i);
    }
    pos_ += static_cast<std::size_t>(bytes);
    return true;
  }
  bool get_signed(Nanos& value) {
    std::uint64_t raw = 0;
    if (!get(raw, 8)) {
      return false;
    }
    value = static_cast<Nanos>(raw);
    return true;
  }
  bool done() const { return pos_ == size_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace detail

inline void encode(const Envelope& e, std::vector<std::uint8_t>& out) {
  out.clear();
  out.reserve(50 + 20 * e.stamps.size());
  out.insert(out.end(), {'V', 'F', 'Y', '2'});
  detail::put(out, e.index, 8);
  detail::put(out, e.seq, 8);
  detail::put(out, static_cast<std::uint64_t>(e.release), 8);
  detail::put(out, static_cast<std::uint64_t>(e.start), 8);
  detail::put(out, static_cast<std::uint64_t>(e.finish), 8);
  detail::put(out, e.event, 8);
  detail::put(out, e.stamps.size(), 2);
  for (const Stamp& s : e.stamps) {
    detail::put(out, s.chain, 2);
    detail::put(out, s.position, 2);
    detail::put(out, static_cast<std::uint64_t>(s.origin), 8);
    detail::put(out, static_cast<std::uint64_t>(s.first), 8);
  }
}

// False (and `e` unspecified) for anything that is not a whole, well-formed record.
inline bool decode(const std::uint8_t* data, std::size_t size, Envelope& e) {
  if (size < 4 || data[0] != 'V' || data[1] != 'F' || data[2] != 'Y' || data[3] != '2') {
    return false;
  }
  detail::Reader r(data + 4, size - 4);
  std::uint64_t n = 0;
  if (!r.get(e.index, 8) || !r.get(e.seq, 8) || !r.get_signed(e.release) || !r.get_signed(e.start) || !r.get_signed(e.finish) ||
      !r.get(e.event, 8) || !r.get(n, 2)) {
    return false;
  }
  e.stamps.clear();
  e.stamps.reserve(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    std::uint64_t chain = 0, position = 0;
    Stamp s;
    if (!r.get(chain, 2) || !r.get(position, 2) || !r.get_signed(s.origin) || !r.get_signed(s.first)) {
      return false;
    }
    s.chain = static_cast<std::uint16_t>(chain);
    s.position = static_cast<std::uint16_t>(position);
    e.stamps.push_back(s);
  }
  return r.done();
}

}  // namespace verify_ros1
