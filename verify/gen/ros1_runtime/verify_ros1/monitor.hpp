// verify_ros1/monitor.hpp: online reaction time, data age and jitter of cause-effect chains, as
// specs/timing.md §4 defines them (specs/codegen.md, "Monitors"). Plain C++ (no ROS): the generated
// nodes feed it, and so can hand-written ones.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "verify_ros1/envelope.hpp"

namespace verify_ros1 {

// A chain's latency specs in ns; 0: no spec of that kind.
struct Bounds {
  Nanos reaction_time = 0;
  Nanos data_age = 0;
  Nanos jitter = 0;
};

struct Violation {
  std::string chain;
  std::string metric;  // "reaction_time", "data_age" or "jitter"
  Nanos value = 0;
  Nanos bound = 0;
  Nanos at = 0;  // the completion that showed it
};

// One latency metric of one chain: exact count, minimum and maximum; percentiles over the first
// kMaxSamples samples (all of them in any run shorter than that).
class Metric {
 public:
  static constexpr std::size_t kMaxSamples = 1000000;

  void add(Nanos value) {
    if (count_ == 0 || value < min_) {
      min_ = value;
    }
    if (count_ == 0 || value > max_) {
      max_ = value;
    }
    ++count_;
    if (samples_.size() < kMaxSamples) {
      samples_.push_back(value);
    }
  }
  std::uint64_t count() const { return count_; }
  Nanos min() const { return min_; }
  Nanos max() const { return max_; }
  std::uint64_t violations = 0;

  // Nearest-rank percentile p (0 < p <= 100) of the kept samples.
  Nanos percentile(int p) const {
    if (samples_.empty()) {
      return 0;
    }
    std::vector<Nanos> sorted(samples_);
    std::sort(sorted.begin(), sorted.end());
    std::size_t rank = (static_cast<std::size_t>(p) * sorted.size() + 99) / 100;
    return sorted[std::max<std::size_t>(rank, 1) - 1];
  }

  std::string json(Nanos bound) const {
    std::ostringstream o;
    o << "{\"count\": " << count_;
    if (count_ > 0) {
      o << ", \"min_ns\": " << min_ << ", \"max_ns\": " << max_ << ", \"p50_ns\": " << percentile(50)
        << ", \"p90_ns\": " << percentile(90) << ", \"p99_ns\": " << percentile(99);
    }
    o << ", \"samples_kept\": " << samples_.size();
    if (bound > 0) {
      o << ", \"bound_ns\": " << bound;
    }
    o << ", \"violations\": " << violations << "}";
    return o.str();
  }

 private:
  std::uint64_t count_ = 0;
  Nanos min_ = 0;
  Nanos max_ = 0;
  std::vector<Nanos> samples_;
};

// The monitor of one chain, fed at every completion of a job of the chain's last task that holds a
// stamp of the chain (specs/timing.md §4):
//   data age       finish - origin, for every such job;
//   reaction time  when the origin is newer than every origin before it: finish - the origin that
//                  reached the end before it. A stimulus just after that earlier read is first sampled
//                  by a later read, whose data first reaches the end with this job. Before any origin
//                  reached the end, the first task's first read stands in for it;
//   jitter         the largest minus the smallest data age so far.
class ChainMonitor {
 public:
  ChainMonitor(std::string name, Bounds bounds) : name_(std::move(name)), bounds_(bounds) {}

  const std::string& name() const { return name_; }
  const Bounds& bounds() const { return bounds_; }

  std::vector<Violation> on_end(const Stamp& stamp, Nanos finish) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Violation> found;
    Nanos age = finish - stamp.origin;
    age_.add(age);
    check(found, age_, "data_age", age, bounds_.data_age, finish);
    if (stamp.origin > last_origin_) {
      Nanos from = last_origin_ != 0 ? last_origin_ : (stamp.first < stamp.origin ? stamp.first : 0);
      if (from != 0) {
        Nanos reaction = finish - from;
        reaction_.add(reaction);
        check(found, reaction_, "reaction_time", reaction, bounds_.reaction_time, finish);
      }
      last_origin_ = stamp.origin;
    }
    Nanos jitter = age_.max() - age_.min();
    if (bounds_.jitter > 0 && jitter > bounds_.jitter && jitter > jitter_reported_) {
      jitter_reported_ = jitter;
      ++jitter_violations_;
      found.push_back(Violation{name_, "jitter", jitter, bounds_.jitter, finish});
    }
    return found;
  }

  std::string summary_json() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::ostringstream o;
    o << "{\"reaction_time\": " << reaction_.json(bounds_.reaction_time)
      << ", \"data_age\": " << age_.json(bounds_.data_age) << ", \"jitter\": {\"value_ns\": "
      << (age_.count() > 0 ? age_.max() - age_.min() : 0);
    if (bounds_.jitter > 0) {
      o << ", \"bound_ns\": " << bounds_.jitter;
    }
    o << ", \"violations\": " << jitter_violations_ << "}}";
    return o.str();
  }

 private:
  void check(std::vector<Violation>& found, Metric& metric, const char* kind, Nanos value, Nanos bound,
             Nanos at) {
    if (bound > 0 && value > bound) {
      ++metric.violations;
      found.push_back(Violation{name_, kind, value, bound, at});
    }
  }

  std::string name_;
  Bounds bounds_;
  mutable std::mutex mutex_;
  Nanos last_origin_ = 0;
  Metric reaction_;
  Metric age_;
  Nanos jitter_reported_ = 0;
  std::uint64_t jitter_violations_ = 0;
};

// A JSON string literal of `text`.
inline std::string json_string(const std::string& text) {
  std::ostringstream o;
  o << '"';
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      o << '\\' << c;
    } else if (c < 0x20) {
      const char* hex = "0123456789abcdef";
      o << "\\u00" << hex[c >> 4] << hex[c & 15];
    } else {
      o << c;
    }
  }
  o << '"';
  return o.str();
}

inline std::string violation_json(const Violation& v) {
  std::ostringstream o;
  o << "{\"chain\": " << json_string(v.chain) << ", \"metric\": " << json_string(v.metric)
    << ", \"value_ns\": " << v.value << ", \"bound_ns\": " << v.bound << ", \"at_ns\": " << v.at << "}";
  return o.str();
}

// The directory for the monitors' summaries (`summary_dir`), made with its parents if need be: "" when
// it is a directory this process may write into, else what is wrong. A node asks when it starts, so that
// a summary that could not be written is reported before the run, not lost after it.
inline std::string prepare_summary_directory(const std::string& directory) {
  std::error_code error;
  if (std::filesystem::exists(directory, error) && !std::filesystem::is_directory(directory, error)) {
    return "the summary directory " + directory + " is not a directory";
  }
  std::filesystem::create_directories(directory, error);
  if (error) {
    return "cannot create the summary directory " + directory + ": " + error.message();
  }
  if (::access(directory.c_str(), W_OK | X_OK) != 0) {
    return "cannot write into the summary directory " + directory + ": " + std::strerror(errno);
  }
  return "";
}

}  // namespace verify_ros1
