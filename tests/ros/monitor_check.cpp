// A hand-written program on the monitor library alone (no ROS, no generated code): known answers of
// ChainMonitor (specs/codegen.md §5), a round trip of the out-of-band record, and the summary directory made
// where it can be and refused where it cannot (argv[1]: an empty scratch directory). Exits 0 when every check
// holds, else prints the failed check and exits 1. Built and run by tests/test_gen_ros1.py.
#include <cstdio>
#include <fstream>
#include <string>

#include "verify_ros1/envelope.hpp"
#include "verify_ros1/monitor.hpp"

namespace {

int failures = 0;

void check(bool ok, const char* what) {
  if (!ok) {
    std::printf("failed: %s\n", what);
    ++failures;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using verify_ros1::Stamp;
  if (argc != 2) {
    std::printf("usage: monitor_check SCRATCH_DIR\n");
    return 2;
  }
  const std::string scratch = argv[1];
  const std::string nested = scratch + "/latency/run1";
  check(verify_ros1::prepare_summary_directory(nested).empty(), "a missing summary directory is made");
  check(std::ofstream(nested + "/n.json").good(), "the summary directory takes a file");
  check(verify_ros1::prepare_summary_directory(nested).empty(), "an existing summary directory is fine");
  std::ofstream(scratch + "/file") << "x";
  const std::string under_file = verify_ros1::prepare_summary_directory(scratch + "/file/sub");
  check(under_file.rfind("cannot create the summary directory " + scratch + "/file/sub: ", 0) == 0,
        "a directory under a file is refused with the reason");
  check(verify_ros1::prepare_summary_directory(scratch + "/file").find("is not a directory") != std::string::npos,
        "a file is not a summary directory");
  // reads of the first task at 100, 200, 300, 400; reaction bound 250, data age bound 150
  verify_ros1::ChainMonitor m("c", verify_ros1::Bounds{250, 150, 60});
  // the data of read 200 reaches the end first, at 330: age 130; reaction from the first read (100): 230
  auto v = m.on_end(Stamp{0, 2, 200, 100}, 330);
  check(v.empty(), "no violation at 330");
  // the same data again at 360: age 160 > 150 (a violation), no new reaction
  v = m.on_end(Stamp{0, 2, 200, 100}, 360);
  check(v.size() == 1 && v[0].metric == "data_age" && v[0].value == 160 && v[0].bound == 150, "age 160");
  // read 400 reaches at 470 (read 300 never did): reaction from 200 (the newest origin before): 270 > 250;
  // age 70; jitter 160 - 70 = 90 > 60
  v = m.on_end(Stamp{0, 2, 400, 100}, 470);
  check(v.size() == 2 && v[0].metric == "reaction_time" && v[0].value == 270 && v[1].metric == "jitter" &&
            v[1].value == 90,
        "reaction 270 and jitter 90");
  const std::string s = m.summary_json();
  check(s.find("\"reaction_time\": {\"count\": 2, \"min_ns\": 230, \"max_ns\": 270") != std::string::npos,
        "summary of reaction times");
  check(s.find("\"data_age\": {\"count\": 3, \"min_ns\": 70, \"max_ns\": 160, \"p50_ns\": 130") != std::string::npos,
        "summary of data ages");
  check(s.find("\"jitter\": {\"value_ns\": 90, \"bound_ns\": 60, \"violations\": 1}") != std::string::npos,
        "summary of jitter");
  // a first origin that is the first read: no reaction (no read before it)
  verify_ros1::ChainMonitor first("d", verify_ros1::Bounds{});
  first.on_end(Stamp{0, 1, 100, 100}, 150);
  check(first.summary_json().find("\"reaction_time\": {\"count\": 0") != std::string::npos, "no reaction sample");

  verify_ros1::Envelope e;
  e.index = 9;
  e.seq = 7;
  e.release = -1;
  e.start = 1795686227200063972;
  e.finish = e.start + 5;
  e.event = 3;
  e.stamps = {Stamp{1, 2, 10, 20}, Stamp{65535, 0, -3, 4}};
  std::vector<std::uint8_t> bytes;
  verify_ros1::encode(e, bytes);
  verify_ros1::Envelope d;
  check(verify_ros1::decode(bytes.data(), bytes.size(), d), "decodes");
  check(d.seq == 7 && d.release == -1 && d.start == e.start && d.finish == e.finish && d.event == 3 &&
            d.stamps.size() == 2 && d.stamps[1].chain == 65535 && d.stamps[1].origin == -3 && d.index == 9,
        "round trip");
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    check(!verify_ros1::decode(bytes.data(), cut, d), "a truncated record is refused");
  }
  bytes.push_back(0);
  check(!verify_ros1::decode(bytes.data(), bytes.size(), d), "trailing bytes are refused");
  return failures == 0 ? 0 : 1;
}
