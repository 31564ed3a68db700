// verify_ros1/runtime.hpp: what every node `verify gen ros1` generates runs on (specs/codegen.md).
// It gives each task the activation and communication semantics of specs/timing.md §1-§3:
//   - inputs are registers (latest value), read together when a job starts; outputs are written when
//     it completes;
//   - a timer releases at phase + k*period on the wall clock (CLOCK_REALTIME), the same instants in
//     every node of the machine; a data trigger counts arrivals (or compound events) and releases at
//     every k-th; an AND compound fires when every member has a value it has not consumed; an OR
//     compound on every arrival; a sporadic task is released from outside (release_task(), or an
//     std_msgs/Empty on ~release/TASK);
//   - a preemptive task runs on a thread of its own, the cooperative tasks of a node share one thread
//     that starts the highest-priority ready job (FIFO among equals); each thread is pinned to its
//     core's CPU and scheduled SCHED_FIFO at the task's priority where the OS allows it (a warning
//     otherwise).
// Periods, phases, prescalers, priorities, CPUs and chain roles are ROS parameters (the generated
// config/parameters.yaml), never code.
// On the wire (specs/codegen.md §6) a port's value is its ROS message on a plain topic (a message type
// bound to none travels as Bytes); the writer job's identity and chain stamps travel out of band, in a
// record on TOPIC/verify that names the message by its number on the topic.
#pragma once

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <exception>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcException.h>
#include <std_msgs/Empty.h>
#include <std_msgs/String.h>
#include <std_msgs/UInt8MultiArray.h>

#include "verify_ros1/envelope.hpp"
#include "verify_ros1/monitor.hpp"

namespace verify_ros1 {

constexpr Nanos kSecond = 1000000000;
// SCHED_FIFO priorities of the middleware's threads (roscpp's own and the arrivals) and of the timers:
// above every task (the generator gives tasks 10 .. 90)
constexpr int kMiddlewarePriority = 97;
constexpr int kTimerPriority = 98;

// The wall clock in ns since the Unix epoch: the time base of every stamp.
inline Nanos now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<Nanos>(ts.tv_sec) * kSecond + ts.tv_nsec;
}

// The CPU time the calling thread has used, in ns (time it is preempted or blocked does not count).
inline Nanos thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<Nanos>(ts.tv_sec) * kSecond + ts.tv_nsec;
}

// Busy for `duration` ns of this thread's own CPU time (time it is preempted does not count): what a
// job with that execution time does to the schedule. For tests and demonstrations.
inline void burn_cpu(Nanos duration) {
  const Nanos end = thread_cpu_ns() + duration;
  while (thread_cpu_ns() < end) {
  }
}

// An exact duration in ns, num/den (the model's times are exact rationals: 1/30 s is 100000000/3 ns).
struct Duration {
  std::int64_t num = 0;
  std::int64_t den = 1;

  static bool parse(const std::string& text, Duration& out) {
    std::size_t slash = text.find('/');
    try {
      std::size_t used = 0;
      out.num = std::stoll(text.substr(0, slash), &used);
      if (used != (slash == std::string::npos ? text.size() : slash)) {
        return false;
      }
      out.den = 1;
      if (slash != std::string::npos) {
        out.den = std::stoll(text.substr(slash + 1), &used);
        if (used != text.size() - slash - 1) {
          return false;
        }
      }
    } catch (const std::exception&) {
      return false;
    }
    return out.den > 0 && out.num >= 0;
  }
};

// Set by SIGINT and SIGTERM (request_stop, installed by main_of); Component::run then stops.
inline std::atomic<bool> g_stop_requested{false};  // (constant-initialised: safe in a signal handler)
inline bool stop_requested() { return g_stop_requested.load(); }
inline void request_stop(int) { g_stop_requested.store(true); }

// Pins the calling thread to `cpu` (if >= 0) and schedules it SCHED_FIFO at `os_priority` (if > 0).
// Returns what could not be done ("" when everything was applied).
inline std::string apply_scheduling(int os_priority, int cpu) {
  std::string problems;
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<std::size_t>(cpu), &set);
    int err = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (err != 0) {
      problems += "CPU " + std::to_string(cpu) + ": " + std::strerror(err) + "; ";
    }
  }
  if (os_priority > 0) {
    sched_param param{};
    param.sched_priority = os_priority;
    int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (err != 0) {
      problems += "SCHED_FIFO " + std::to_string(os_priority) + ": " + std::strerror(err) +
                  " (grant CAP_SYS_NICE or an rtprio limit to get real-time scheduling)";
    }
  }
  return problems;
}

// A value a job read on an in-port: the latest that arrived before the job started, or none.
template <class T>
class Input {
 public:
  bool has_value() const { return value_ != nullptr; }
  explicit operator bool() const { return has_value(); }
  // The value; a default-constructed T when none has arrived (specs/timing.md §2).
  const T& value() const { return value_ ? *value_ : empty(); }
  const T& operator*() const { return value(); }
  const T* operator->() const { return &value(); }
  // The number of the writer's job that produced it (0: none).
  std::uint64_t seq() const { return seq_; }

  std::shared_ptr<const T> value_;
  std::uint64_t seq_ = 0;

 private:
  static const T& empty() {
    static const T nothing{};
    return nothing;
  }
};

struct Task;

// One job of a task, from its start to its completion.
struct Job {
  Task* task = nullptr;
  std::uint64_t seq = 0;
  Nanos release = 0;
  Nanos start = 0;
  Nanos finish = 0;
  Nanos cpu_start = 0;  // the thread's CPU clock at the start
  Nanos cpu = 0;        // the CPU time the job's thread spent from its start to its finish
  std::uint64_t event = 0;
  std::uint64_t trigger_seq = 0;
  std::vector<std::pair<std::string, const std::vector<Stamp>*>> inputs;  // stamps per in-port read
  std::vector<std::shared_ptr<const std::vector<Stamp>>> keep;           // (owning the above)
  std::vector<std::pair<std::string, std::uint64_t>> read_seqs;
  std::vector<std::pair<std::string, Stamp>> held;  // (out-port or "" at a chain's end, stamp)

  void hold();
  std::vector<Stamp> stamps_for(const std::string& port) const {
    std::vector<Stamp> out;
    for (const auto& h : held) {
      if (h.first == port) {
        out.push_back(h.second);
      }
    }
    return out;
  }
};

// The part a task plays in a chain (specs/codegen.md, "Chain stamps"): at `position` of chain
// `chain`, it takes the stamp from in-port `from` ("" for the chain's first task: its own start) and
// passes it on out-port `to` ("" for the chain's last task, whose monitor takes it).
struct ChainRole {
  std::uint16_t chain = 0;
  std::uint16_t position = 0;
  std::string from;
  std::string to;
};

struct Release {
  Nanos time = 0;
  std::uint64_t event = 0;
  std::uint64_t trigger_seq = 0;
};

struct Task {
  std::string name;
  bool cooperative = false;
  std::function<void(Job&)> body;
  // from the parameters
  std::string activation;  // "timer", "trigger" or "sporadic"
  Duration period, phase;
  std::string trigger;
  std::uint64_t prescaler = 1;
  Nanos sporadic_min = 0, sporadic_max = 0;
  int priority = 0, os_priority = 0, cpu = -1;
  std::vector<ChainRole> roles;
  // state
  std::uint64_t events = 0;
  std::uint64_t seq = 0;
  Nanos first_start = 0;
  Nanos last_sporadic = 0;
  class Executor* executor = nullptr;
};

inline void Job::hold() {
  held.clear();
  for (const ChainRole& role : task->roles) {
    if (role.from.empty()) {
      held.emplace_back(role.to, Stamp{role.chain, role.position, start, task->first_start != 0 ? task->first_start : start});
      continue;
    }
    for (const auto& input : inputs) {
      if (input.first != role.from) {
        continue;
      }
      for (const Stamp& s : *input.second) {
        if (s.chain == role.chain && s.position + 1 == role.position) {
          held.emplace_back(role.to, Stamp{role.chain, role.position, s.origin, s.first});
        }
      }
    }
  }
}

// What a message type bound to no ROS message travels as: its value serialized by ros::serialization.
using Bytes = std_msgs::UInt8MultiArray;

// The value of a message as it arrived (W: the wire type, T: the port's value type); null when it does
// not deserialize.
template <class T, class W>
std::shared_ptr<const T> from_wire(const boost::shared_ptr<const W>& message) {
  if constexpr (std::is_same<T, W>::value) {
    return std::shared_ptr<const T>(message.get(), [message](const T*) {});  // (shares the message)
  } else {
    static_assert(std::is_same<W, Bytes>::value, "a message type is its ROS message or Bytes");
    auto value = std::make_shared<T>();
    try {
      ros::serialization::IStream stream(const_cast<std::uint8_t*>(message->data.data()),
                                         static_cast<std::uint32_t>(message->data.size()));
      ros::serialization::deserialize(stream, *value);
    } catch (const std::exception&) {
      return nullptr;
    }
    return value;
  }
}

// The register of an in-port, and the pairing of its messages with their out-of-band records.
template <class T, class W = T>
class InPort {
 public:
  using Wire = W;
  explicit InPort(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }

  // At a job's start, with the registers locked.
  void read(Input<T>& into, Job& job) const {
    into.value_ = value_;
    into.seq_ = seq_;
    if (value_) {
      job.keep.push_back(stamps_);
      job.inputs.emplace_back(name_, stamps_.get());
      job.read_seqs.emplace_back(name_, seq_);
    }
  }
  // At an arrival, with the registers locked.
  void store(std::shared_ptr<const T> value, std::vector<Stamp> stamps, std::uint64_t seq) {
    value_ = std::move(value);
    stamps_ = std::make_shared<const std::vector<Stamp>>(std::move(stamps));
    seq_ = seq;
  }

  // A message from the model's writer: the index-th on the topic, waiting for its record (or the value
  // null: it did not deserialize, but it is counted).
  struct Waiting {
    std::uint64_t index = 0;
    std::shared_ptr<const T> value;
  };
  ros::Subscriber subscriber, record_subscriber;
  std::string source;  // the node of the model that writes the topic ("": none)
  std::uint64_t received = 0;  // messages from the source so far
  std::deque<Waiting> waiting;
  std::map<std::uint64_t, Envelope> records;  // records that came before their messages, by index

 private:
  std::string name_;
  std::shared_ptr<const T> value_;
  std::shared_ptr<const std::vector<Stamp>> stamps_ = std::make_shared<const std::vector<Stamp>>();
  std::uint64_t seq_ = 0;
};

template <class T, class W = T>
class OutPort {
 public:
  using Wire = W;
  explicit OutPort(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }

  // At a job's completion: the record of the message (the job's identity and the chain stamps it
  // carries; when records are on), then the value as its ROS message.
  void write(const T& value, const Job& job) {
    ++index_;
    if (records) {
      Envelope e;
      e.index = index_;
      e.seq = job.seq;
      e.release = job.release;
      e.start = job.start;
      e.finish = job.finish;
      e.event = job.event;
      e.stamps = job.stamps_for(name_);
      Bytes record;
      encode(e, record.data);
      record_publisher.publish(record);
    }
    if constexpr (std::is_same<T, W>::value) {
      publisher.publish(value);
    } else {
      Bytes message;
      message.data.resize(ros::serialization::serializationLength(value));
      ros::serialization::OStream stream(message.data.data(), static_cast<std::uint32_t>(message.data.size()));
      ros::serialization::serialize(stream, value);
      publisher.publish(message);
    }
  }

  ros::Publisher publisher, record_publisher;
  bool records = false;

 private:
  std::string name_;
  std::uint64_t index_ = 0;
};

// A thread that runs jobs: one per preemptive task, one for the cooperative tasks of a node.
class Executor {
 public:
  Executor(std::string name, int cpu, int os_priority) : name_(std::move(name)), cpu_(cpu), os_priority_(os_priority) {}

  void push(Task* task, const Release& release) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ready_.push_back(Entry{task, release, order_++});
    }
    wake_.notify_one();
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopped_ = true;
    }
    wake_.notify_all();
  }

  template <class RunJob>
  void run(RunJob&& run_job) {
    std::string problems = apply_scheduling(os_priority_, cpu_);
    if (!problems.empty()) {
      ROS_WARN("%s: %s", name_.c_str(), problems.c_str());
    }
    int current = os_priority_;
    for (;;) {
      Entry next;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stopped_ || !ready_.empty(); });
        if (stopped_) {
          return;
        }
        auto best = std::min_element(ready_.begin(), ready_.end(), [](const Entry& a, const Entry& b) {
          if (a.task->priority != b.task->priority) {
            return a.task->priority > b.task->priority;
          }
          if (a.release.time != b.release.time) {
            return a.release.time < b.release.time;
          }
          return a.order < b.order;
        });
        next = *best;
        ready_.erase(best);
      }
      if (next.task->os_priority != current && next.task->os_priority > 0) {
        sched_param param{};
        param.sched_priority = next.task->os_priority;
        if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0) {
          current = next.task->os_priority;
        }
      }
      run_job(next.task, next.release);
    }
  }

 private:
  struct Entry {
    Task* task = nullptr;
    Release release;
    std::uint64_t order = 0;
  };
  std::string name_;
  int cpu_;
  int os_priority_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Entry> ready_;
  std::uint64_t order_ = 0;
  bool stopped_ = false;
};

// The base of every generated component glue class.
class Component {
 public:
  Component(ros::NodeHandle nh, ros::NodeHandle pnh, std::string component)
      : nh_(std::move(nh)), pnh_(std::move(pnh)), component_(std::move(component)) {}
  virtual ~Component() = default;
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  // Runs the node until ROS shuts down (SIGINT), then writes the monitors' summary. 0 on success.
  int run();

  // Releases the sporadic task `task` now (for code that drives it from outside).
  void release_task(const std::string& task);

 protected:
  // Subscribes the in-port to the topic of its connection (parameter topics/PORT; none: unconnected).
  // (specs/codegen.md §6: the port's messages on TOPIC, their records on TOPIC/verify, paired by the
  // message's number on the topic; a message from a node other than the model's writer is data without
  // stamps)
  template <class T, class W>
  void subscribe(InPort<T, W>& port) {
    std::string topic;
    if (!pnh_.getParam("topics/" + port.name(), topic)) {
      return;
    }
    pnh_.param("sources/" + port.name(), port.source, std::string());
    using Event = ros::MessageEvent<W const>;
    port.subscriber = nh_.subscribe<W, const Event&>(
        topic, 100, boost::function<void(const Event&)>([this, &port](const Event& event) {
          arrive(port, event.getPublisherName(), event.getConstMessage());
        }),
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    if (records()) {
      using RecordEvent = ros::MessageEvent<Bytes const>;
      port.record_subscriber = nh_.subscribe<Bytes, const RecordEvent&>(
          topic + "/verify", 100, boost::function<void(const RecordEvent&)>([this, &port](const RecordEvent& event) {
            arrive_record(port, event.getPublisherName(), *event.getConstMessage());
          }),
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    }
    connected_.emplace_back("in-port " + port.name() + " (" + topic + ")",
                            [&port] { return port.subscriber.getNumPublishers() >= 1; });
  }
  template <class T, class W>
  void advertise(OutPort<T, W>& port) {
    const std::string topic = ros::this_node::getName() + "/" + port.name();
    port.publisher = nh_.advertise<W>(topic, 100);
    port.records = records();
    if (port.records) {
      port.record_publisher = nh_.advertise<Bytes>(topic + "/verify", 100);
    }
    int readers = 0;
    pnh_.param("subscribers/" + port.name(), readers, 0);
    connected_.emplace_back("out-port " + port.name(), [&port, readers] {
      const auto n = static_cast<std::uint32_t>(readers);
      return port.publisher.getNumSubscribers() >= n && (!port.records || port.record_publisher.getNumSubscribers() >= n);
    });
  }
  // Whether records travel beside the messages: with monitors or a trace (launch arguments).
  bool records() {
    bool monitor = true, trace = false;
    pnh_.param("/verify/monitor", monitor, true);
    pnh_.param("/verify/trace", trace, false);
    return monitor || trace;
  }
  void declare_compound(const std::string& name, bool all, std::vector<std::string> members) {
    compounds_.push_back(Compound{name, all, std::move(members), {}});
  }
  void declare_task(const std::string& name, bool cooperative, std::function<void(Job&)> body) {
    auto task = std::make_unique<Task>();
    task->name = name;
    task->cooperative = cooperative;
    task->body = std::move(body);
    tasks_.push_back(std::move(task));
  }
  // Reads the parameters of every task; false (after logging why) when they are missing or invalid.
  bool configure();
  std::mutex& registers() { return registers_; }

 private:
  struct Compound {
    std::string name;
    bool all;
    std::vector<std::string> members;
    std::vector<std::string> fresh;  // AND: members with a value not yet consumed
  };

  // A message on an in-port (on the arrival thread): from the model's writer, it waits for its record
  // (unless records are off, or no record publisher is connected); from any other node it is data
  // without stamps, stored at once.
  template <class T, class W>
  void arrive(InPort<T, W>& port, const std::string& publisher, const boost::shared_ptr<const W>& message) {
    std::shared_ptr<const T> value = from_wire<T, W>(message);
    if (!value) {
      ROS_WARN_THROTTLE(1.0, "%s: a message on in-port %s does not deserialize as its type; dropped",
                        name().c_str(), port.name().c_str());
    }
    if (publisher != port.source || port.source.empty() || port.record_subscriber.getNumPublishers() == 0) {
      if (value) {
        deliver(port, std::move(value), {}, 0);
      }
      return;
    }
    port.waiting.push_back({++port.received, std::move(value)});
    pair_records(port);
  }
  template <class T, class W>
  void arrive_record(InPort<T, W>& port, const std::string& publisher, const Bytes& message) {
    Envelope record;
    if (publisher != port.source || !decode(message.data.data(), message.data.size(), record)) {
      ROS_WARN_THROTTLE(1.0, "%s: a record on in-port %s's topic is not the writer's (%s) or not a record; dropped",
                        name().c_str(), port.name().c_str(), publisher.c_str());
      return;
    }
    if (record.index > port.received || !port.waiting.empty()) {  // (else its message went by: stale)
      port.records[record.index] = std::move(record);
    }
    pair_records(port);
  }
  // Stores the waiting messages, in order, whose records are here; a message whose record has been
  // overtaken by a later one (lost) is stored without stamps; so is the oldest beyond 100 waiting.
  template <class T, class W>
  void pair_records(InPort<T, W>& port) {
    while (!port.waiting.empty()) {
      auto& next = port.waiting.front();
      auto record = port.records.find(next.index);
      const bool lost = record == port.records.end() &&
                        ((!port.records.empty() && port.records.rbegin()->first > next.index) ||
                         port.waiting.size() > 100);
      if (record == port.records.end() && !lost) {
        return;
      }
      if (next.value) {
        if (lost) {
          deliver(port, std::move(next.value), {}, 0);
        } else {
          deliver(port, std::move(next.value), std::move(record->second.stamps), record->second.seq);
        }
      }
      port.records.erase(port.records.begin(), port.records.upper_bound(next.index));
      port.waiting.pop_front();
    }
  }
  template <class T, class W>
  void deliver(InPort<T, W>& port, std::shared_ptr<const T> value, std::vector<Stamp> stamps, std::uint64_t seq) {
    std::lock_guard<std::mutex> lock(registers_);
    port.store(std::move(value), std::move(stamps), seq);
    arrived(port.name(), seq);
  }
  void arrived(const std::string& port, std::uint64_t seq);
  void event(const std::string& trigger, std::uint64_t seq);
  void run_job(Task* task, const Release& release);
  void after_job(const Job& job);
  void timer_loop(Task* task);
  std::string name() const { return ros::this_node::getName(); }
  bool read_task(Task& task);
  bool read_roles(Task& task);

  ros::NodeHandle nh_, pnh_;
  std::string component_;
  std::vector<std::unique_ptr<Task>> tasks_;
  std::vector<Compound> compounds_;
  std::vector<std::unique_ptr<Executor>> executors_;
  std::map<std::uint16_t, std::unique_ptr<ChainMonitor>> monitors_;
  std::mutex registers_;
  std::atomic<bool> stopping_{false};
  std::mutex timers_mutex_;
  std::condition_variable timers_wake_;
  bool trace_ = false;
  bool monitor_ = true;
  ros::Publisher violations_, jobs_;
  std::vector<ros::Subscriber> release_subscribers_;
  std::vector<std::pair<std::string, std::function<bool()>>> connected_;  // (what, whether it is connected)

  void await_connections();
  Nanos agree_on_start();
};

// Every connection of the node established (specs/timing.md §2 has every value written delivered: a
// message published before its subscriber is connected would be lost). At most 30 s, then a warning.
inline void Component::await_connections() {
  for (int i = 0; i < 3000 && ros::ok() && !stop_requested(); ++i) {
    bool all = std::all_of(connected_.begin(), connected_.end(), [](const auto& c) { return c.second(); });
    if (all) {
      return;
    }
    ros::WallDuration(0.01).sleep();
  }
  if (stop_requested()) {
    return;  // (asked to stop while starting: nothing to warn about)
  }
  for (const auto& c : connected_) {
    if (!c.second()) {
      ROS_WARN("%s: %s is not connected after 30 s; starting anyway", name().c_str(), c.first.c_str());
    }
  }
}

// The instant every node of the launch starts its timers: each node, once connected, records when on
// the parameter server (/verify/ready/RUN/NODE); when all have, each computes the same instant, 200 ms
// after the last. Without a run (a node started by hand): now. See specs/codegen.md, "Start".
inline Nanos Component::agree_on_start() {
  std::string run;
  std::vector<std::string> nodes;
  if (!ros::param::get("/verify/run", run) || !nh_.getParam("nodes", nodes)) {
    return now_ns();
  }
  std::string self = ros::this_node::getName();
  self = self.substr(self.rfind('/') + 1);
  const std::string ready = "/verify/ready/" + run + "/";
  ros::param::set(ready + self, std::to_string(now_ns()));
  for (int i = 0; i < 3000 && ros::ok() && !stop_requested(); ++i) {
    Nanos last = 0;
    bool all = true;
    for (const std::string& node : nodes) {
      std::string at;
      if (!ros::param::getCached(ready + node, at)) {
        all = false;
        break;
      }
      last = std::max<Nanos>(last, std::stoll(at));
    }
    if (all) {
      return last + kSecond / 5;
    }
    ros::WallDuration(0.01).sleep();
  }
  if (!stop_requested()) {
    ROS_WARN("%s: not every node of the launch was ready after 30 s; starting anyway", name().c_str());
  }
  return now_ns();
}

inline bool Component::configure() {
  pnh_.param("/verify/trace", trace_, false);
  pnh_.param("/verify/monitor", monitor_, true);
  bool ok = true;
  for (auto& task : tasks_) {
    ok = read_task(*task) && ok;
  }
  if (!ok) {
    return false;
  }
  std::map<std::string, Executor*> cooperative;  // one thread for all cooperative tasks of the node
  for (auto& task : tasks_) {
    if (task->cooperative) {
      Executor*& shared = cooperative["cooperative"];
      if (shared == nullptr) {
        executors_.push_back(std::make_unique<Executor>(name() + " cooperative", task->cpu, task->os_priority));
        shared = executors_.back().get();
      }
      task->executor = shared;
    } else {
      executors_.push_back(std::make_unique<Executor>(name() + "/" + task->name, task->cpu, task->os_priority));
      task->executor = executors_.back().get();
    }
    if (task->activation == "sporadic") {
      Task* raw = task.get();
      release_subscribers_.push_back(pnh_.subscribe<std_msgs::Empty>(
          "release/" + task->name, 10, [this, raw](const std_msgs::Empty::ConstPtr&) { release_task(raw->name); }));
    }
  }
  violations_ = nh_.advertise<std_msgs::String>("/verify/violations", 100);
  if (trace_) {
    jobs_ = nh_.advertise<std_msgs::String>("/verify/jobs", 1000);
  }
  return true;
}

inline bool Component::read_task(Task& task) {
  const std::string key = "tasks/" + task.name + "/";
  auto fail = [&](const std::string& what) {
    ROS_ERROR("%s: parameter %s%s: %s (regenerate config/parameters.yaml with `verify gen ros1`)", name().c_str(),
              key.c_str(), what.c_str(), "missing or invalid");
    return false;
  };
  if (!pnh_.getParam(key + "activation", task.activation)) {
    return fail("activation");
  }
  pnh_.param(key + "priority", task.priority, 0);
  pnh_.param(key + "os_priority", task.os_priority, 0);
  pnh_.param(key + "cpu", task.cpu, -1);
  if (task.activation == "timer") {
    std::string period, phase;
    if (!pnh_.getParam(key + "period_ns", period) || !Duration::parse(period, task.period) || task.period.num == 0) {
      return fail("period_ns");
    }
    pnh_.param(key + "phase_ns", phase, std::string("0"));
    if (!Duration::parse(phase, task.phase)) {
      return fail("phase_ns");
    }
  } else if (task.activation == "trigger") {
    int prescaler = 1;
    if (!pnh_.getParam(key + "trigger", task.trigger)) {
      return fail("trigger");
    }
    pnh_.param(key + "prescaler", prescaler, 1);
    if (prescaler < 1) {
      return fail("prescaler");
    }
    task.prescaler = static_cast<std::uint64_t>(prescaler);
  } else if (task.activation == "sporadic") {
    std::string low, high;
    Duration a, b;
    if (!pnh_.getParam(key + "min_ns", low) || !Duration::parse(low, a)) {
      return fail("min_ns");
    }
    if (!pnh_.getParam(key + "max_ns", high) || !Duration::parse(high, b)) {
      return fail("max_ns");
    }
    task.sporadic_min = a.num / a.den;
    task.sporadic_max = b.num / b.den;
  } else {
    return fail("activation");
  }
  return read_roles(task);
}

inline bool Component::read_roles(Task& task) {
  XmlRpc::XmlRpcValue roles;
  if (!monitor_ || !pnh_.getParam("tasks/" + task.name + "/chains", roles)) {
    return true;  // on no chain, or monitoring off: no stamps, no monitors
  }
  if (roles.getType() != XmlRpc::XmlRpcValue::TypeArray) {
    ROS_ERROR("%s: parameter tasks/%s/chains is not a list", name().c_str(), task.name.c_str());
    return false;
  }
  for (int i = 0; i < roles.size(); ++i) {
    XmlRpc::XmlRpcValue& r = roles[i];
    try {
      ChainRole role;
      role.chain = static_cast<std::uint16_t>(static_cast<int>(r["chain"]));
      role.position = static_cast<std::uint16_t>(static_cast<int>(r["position"]));
      role.from = static_cast<std::string>(r["from"]);
      role.to = static_cast<std::string>(r["to"]);
      task.roles.push_back(role);
      if (role.to.empty()) {
        auto ns = [&r](const char* field) -> Nanos {
          if (!r.hasMember(field)) {
            return 0;
          }
          Duration d;
          return Duration::parse(static_cast<std::string>(r[field]), d) ? d.num / d.den : 0;
        };
        Bounds bounds{ns("reaction_time_ns"), ns("data_age_ns"), ns("jitter_ns")};
        monitors_[role.chain] = std::make_unique<ChainMonitor>(static_cast<std::string>(r["name"]), bounds);
      }
    } catch (const XmlRpc::XmlRpcException& err) {
      ROS_ERROR("%s: parameter tasks/%s/chains[%d]: %s", name().c_str(), task.name.c_str(), i,
                err.getMessage().c_str());
      return false;
    }
  }
  return true;
}

inline void Component::arrived(const std::string& port, std::uint64_t seq) {
  event(port, seq);
  for (Compound& c : compounds_) {
    if (std::find(c.members.begin(), c.members.end(), port) == c.members.end()) {
      continue;
    }
    if (!c.all) {
      event(c.name, seq);
      continue;
    }
    if (std::find(c.fresh.begin(), c.fresh.end(), port) == c.fresh.end()) {
      c.fresh.push_back(port);
    }
    if (c.fresh.size() == c.members.size()) {
      c.fresh.clear();  // the event consumes the freshness of every member
      event(c.name, seq);
    }
  }
}

inline void Component::event(const std::string& trigger, std::uint64_t seq) {
  const Nanos now = now_ns();
  for (auto& task : tasks_) {
    if (task->activation != "trigger" || task->trigger != trigger) {
      continue;
    }
    ++task->events;
    if (task->events % task->prescaler == 0) {
      task->executor->push(task.get(), Release{now, task->events, seq});
    }
  }
}

inline void Component::release_task(const std::string& name_of_task) {
  const Nanos now = now_ns();
  for (auto& task : tasks_) {
    if (task->name != name_of_task || task->activation != "sporadic") {
      continue;
    }
    std::uint64_t index = 0;
    {
      std::lock_guard<std::mutex> lock(registers_);
      if (task->last_sporadic != 0 && now - task->last_sporadic < task->sporadic_min) {
        ROS_WARN_THROTTLE(1.0, "%s: %s released %.3f ms after its previous release, below the modelled minimum "
                          "inter-arrival time %.3f ms", name().c_str(), task->name.c_str(),
                          static_cast<double>(now - task->last_sporadic) / 1e6,
                          static_cast<double>(task->sporadic_min) / 1e6);
      }
      task->last_sporadic = now;
      index = ++task->events;
    }
    task->executor->push(task.get(), Release{now, index, 0});
  }
}

inline void Component::run_job(Task* task, const Release& release) {
  Job job;
  job.task = task;
  job.seq = ++task->seq;
  job.release = release.time;
  job.event = release.event;
  job.trigger_seq = release.trigger_seq;
  try {
    task->body(job);
  } catch (const std::exception& err) {  // (the functional code's: the job writes nothing, the node goes on)
    ROS_ERROR_THROTTLE(1.0, "%s: %s failed: %s; its outputs were not written", name().c_str(), task->name.c_str(),
                       err.what());
    return;
  }
  if (task->first_start == 0) {
    task->first_start = job.start;
  }
  after_job(job);
}

inline void Component::after_job(const Job& job) {
  for (const auto& h : job.held) {
    if (!h.first.empty()) {
      continue;
    }
    auto monitor = monitors_.find(h.second.chain);
    if (monitor == monitors_.end()) {
      continue;
    }
    for (const Violation& v : monitor->second->on_end(h.second, job.finish)) {
      ROS_WARN_THROTTLE(1.0, "chain %s: %s %.3f ms exceeds its spec %.3f ms (every violation is published on "
                        "/verify/violations)", v.chain.c_str(), v.metric.c_str(), static_cast<double>(v.value) / 1e6,
                        static_cast<double>(v.bound) / 1e6);
      std_msgs::String message;
      message.data = violation_json(v);
      violations_.publish(message);
    }
  }
  if (!trace_) {
    return;
  }
  std::ostringstream o;
  o << "{\"node\": " << json_string(name()) << ", \"task\": " << json_string(job.task->name) << ", \"seq\": "
    << job.seq << ", \"release\": " << job.release << ", \"start\": " << job.start << ", \"finish\": " << job.finish
    << ", \"cpu\": " << job.cpu << ", \"event\": " << job.event << ", \"trigger_seq\": " << job.trigger_seq
    << ", \"reads\": {";
  for (std::size_t i = 0; i < job.read_seqs.size(); ++i) {
    o << (i ? ", " : "") << json_string(job.read_seqs[i].first) << ": " << job.read_seqs[i].second;
  }
  o << "}, \"held\": [";
  for (std::size_t i = 0; i < job.held.size(); ++i) {
    const Stamp& s = job.held[i].second;
    o << (i ? ", " : "") << "[" << s.chain << ", " << s.position << ", " << s.origin << ", " << s.first << ", "
      << json_string(job.held[i].first) << "]";
  }
  o << "]}";
  std_msgs::String message;
  message.data = o.str();
  jobs_.publish(message);
}

inline void Component::timer_loop(Task* task) {
  std::string problems = apply_scheduling(kTimerPriority, task->cpu);
  if (!problems.empty()) {
    ROS_WARN("%s: timer of %s: %s", name().c_str(), task->name.c_str(), problems.c_str());
  }
  // release k is at floor(phase + k * period) ns since the epoch: the same instants in every node
  using Wide = __int128;
  const Wide pn = task->phase.num, pd = task->phase.den, tn = task->period.num, td = task->period.den;
  auto at = [&](Wide k) { return static_cast<Nanos>((pn * td + k * tn * pd) / (pd * td)); };
  Wide k = ((static_cast<Wide>(now_ns()) * pd - pn) * td + tn * pd - 1) / (tn * pd) + 1;
  std::unique_lock<std::mutex> lock(timers_mutex_);
  while (!stopping_) {
    const Nanos next = at(k);
    const auto deadline = std::chrono::system_clock::time_point(
        std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::nanoseconds(next)));
    if (timers_wake_.wait_until(lock, deadline, [this] { return stopping_.load(); })) {
      break;
    }
    if (now_ns() < next) {
      continue;  // (woken early)
    }
    task->executor->push(task, Release{now_ns(), static_cast<std::uint64_t>(k), 0});
    ++k;
  }
}

inline int Component::run() {
  if (!configure()) {
    return 1;
  }
  std::string summary_dir;  // (made now, or the node stops now: a summary is not lost after the run)
  if (!monitors_.empty() && ros::param::get("/verify/summary_dir", summary_dir) && !summary_dir.empty()) {
    const std::string problem = prepare_summary_directory(summary_dir);
    if (!problem.empty()) {
      ROS_FATAL("%s: summary_dir:=%s: %s (choose a directory the node may create or write into)", name().c_str(),
                summary_dir.c_str(), problem.c_str());
      return 1;
    }
  }
  if (trace_) {  // a trace is for a recorder: wait (up to 10 s) until one listens, so that it sees every job
    for (int i = 0; i < 1000 && jobs_.getNumSubscribers() == 0 && ros::ok() && !stop_requested(); ++i) {
      ros::WallDuration(0.01).sleep();
    }
  }
  await_connections();
  const Nanos start = agree_on_start();
  for (Nanos left = start - now_ns(); left > 0 && ros::ok() && !stop_requested(); left = start - now_ns()) {
    ros::WallDuration(static_cast<double>(std::min<Nanos>(left, kSecond / 100)) / 1e9).sleep();
  }
  std::vector<std::thread> threads;
  for (auto& executor : executors_) {
    Executor* raw = executor.get();
    threads.emplace_back([this, raw] { raw->run([this](Task* t, const Release& r) { run_job(t, r); }); });
  }
  // arrivals are handled on a thread of their own, above every task (specs/codegen.md)
  threads.emplace_back([this] {
    std::string problems = apply_scheduling(kMiddlewarePriority, -1);
    if (!problems.empty()) {
      ROS_WARN("%s: arrivals: %s", name().c_str(), problems.c_str());
    }
    // Once ROS starts shutting down, the queue is disabled and returns at once: the loop must end
    // then, or this real-time thread would spin and starve the thread that completes the shutdown.
    ros::CallbackQueue* queue = ros::getGlobalCallbackQueue();
    while (!stopping_ && ros::ok() && !ros::isShuttingDown() && queue->isEnabled()) {
      queue->callAvailable(ros::WallDuration(0.01));
    }
  });
  for (auto& task : tasks_) {
    if (task->activation == "timer") {
      Task* raw = task.get();
      threads.emplace_back([this, raw] { timer_loop(raw); });
    }
  }
  // A graceful stop (SIGINT or SIGTERM, as roslaunch stops nodes): no new release; the job that runs
  // completes, and what it publishes (outputs, trace, violations) leaves while ROS is still up; then ROS
  // shuts down. So every job the monitors count was published.
  while (!stop_requested() && ros::ok()) {
    ros::WallDuration(0.02).sleep();
  }
  {
    std::lock_guard<std::mutex> lock(timers_mutex_);
    stopping_ = true;
  }
  timers_wake_.notify_all();
  for (auto& executor : executors_) {
    executor->stop();
  }
  for (auto& thread : threads) {
    thread.join();
  }
  ros::WallDuration(0.25).sleep();  // (roscpp's own threads send what is queued)
  ros::shutdown();
  std::string directory;
  if (!monitors_.empty() && ros::param::get("/verify/summary_dir", directory) && !directory.empty()) {
    std::string node = name().substr(1);
    std::replace(node.begin(), node.end(), '/', '_');
    std::ofstream out(directory + "/" + node + ".json");
    out << "{\"node\": " << json_string(name()) << ", \"chains\": {";
    bool first = true;
    for (const auto& m : monitors_) {
      out << (first ? "" : ", ") << json_string(m.second->name()) << ": " << m.second->summary_json();
      first = false;
    }
    out << "}}\n";
    if (!out) {
      ROS_ERROR("%s: cannot write the monitor summary to %s", name().c_str(), directory.c_str());
      return 1;
    }
  }
  return 0;
}

// The main of a generated node: ros::init, the user's component class, run.
// roscpp's threads, started by ros::init and the first NodeHandle, inherit the middleware priority.
// SIGINT and SIGTERM request the graceful stop of Component::run.
template <class UserComponent>
int main_of(int argc, char** argv, const char* default_name) {
  std::string problems = apply_scheduling(kMiddlewarePriority, -1);
  ros::init(argc, argv, default_name, ros::init_options::NoSigintHandler);
  std::signal(SIGINT, request_stop);
  std::signal(SIGTERM, request_stop);
  if (!problems.empty()) {
    ROS_WARN("%s: middleware threads: %s", ros::this_node::getName().c_str(), problems.c_str());
  }
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  UserComponent component(nh, pnh);
  return component.run();
}

}  // namespace verify_ros1
