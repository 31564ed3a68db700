// The monitors' own work per chain hop and per chain end, in ns (benchmarks/ros1.py, stage
// ros1-monitor): what a job does with monitoring on and does not do with it off.
//   hop: hold() takes the stamp from the input and passes it on, stamps_for() picks it for the
//        out-port, and its 20 bytes are encoded into the message's out-of-band record and decoded by
//        the reader (specs/codegen.md §6);
//   end: ChainMonitor::on_end (data age, reaction time, jitter, spec checks).
// The baseline of each is the same work with no chain role (a record without stamps).
// Prints one JSON object.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "verify_ros1/runtime.hpp"

using verify_ros1::Nanos;

namespace {

volatile std::size_t g_sink = 0;

double per_iteration(int n, bool with_stamps) {
  verify_ros1::Task task;
  if (with_stamps) {
    task.roles.push_back(verify_ros1::ChainRole{0, 1, "in", "out"});
  }
  std::vector<verify_ros1::Stamp> incoming;
  if (with_stamps) {
    incoming.push_back(verify_ros1::Stamp{0, 0, 1000, 10});
  }
  std::vector<std::uint8_t> buffer;
  verify_ros1::Envelope decoded;
  const auto begin = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    verify_ros1::Job job;
    job.task = &task;
    job.start = i;
    job.inputs.emplace_back("in", &incoming);
    job.hold();
    verify_ros1::Envelope e;
    e.seq = static_cast<std::uint64_t>(i);
    e.stamps = job.stamps_for("out");
    verify_ros1::encode(e, buffer);
    verify_ros1::decode(buffer.data(), buffer.size(), decoded);
    g_sink = g_sink + decoded.stamps.size();
  }
  const auto end = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(end - begin).count() / n;
}

double per_end(int n) {
  verify_ros1::ChainMonitor monitor("c", verify_ros1::Bounds{250000000, 200000000, 0});
  const auto begin = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    Nanos origin = 1000000 + static_cast<Nanos>(i / 3) * 25000000;
    g_sink = g_sink + monitor.on_end(verify_ros1::Stamp{0, 3, origin, 1000000}, origin + 150000000).size();
  }
  const auto end = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(end - begin).count() / n;
}

}  // namespace

int main() {
  const int n = 1000000;
  per_iteration(n / 10, true);  // (warm-up)
  const double plain = per_iteration(n, false);
  const double stamped = per_iteration(n, true);
  const double end = per_end(n);
  std::printf("{\"hop_plain_ns\": %.1f, \"hop_monitored_ns\": %.1f, \"end_ns\": %.1f}\n", plain, stamped, end);
  return 0;
}
