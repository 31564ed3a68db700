/* A talker and a listener as ROS 2 records them, without ROS: the `ros2` provider's events
 * (ros2_tp.h: ros2_tracing's names and fields) of a node `/talker` whose timer callback runs every
 * PERIOD_US and burns the given times, publishing `/chatter` each time, and a node `/listener` whose
 * subscription callback takes the message DELAY_US (default 0) after its publish and then burns
 * LISTENER_US. A message is linked as ros2_tracing links it: `rmw_publish` gives the published message
 * its source timestamp, and `rmw_take` carries it. With INTRA_US, a node `/intra_listener` in the same
 * process also subscribes `/chatter`, intra-process as rclcpp and CARET record it (the subscription's
 * intra-process waitable with a callback of its own; `rclcpp_intra_publish` before the inter-process
 * publish, `dispatch_intra_process_subscription_callback` with the message's address and timestamp):
 * it takes each message INTRA_US after its intra-process publish, right after the talker's job.
 * For tests/test_trace_lttng.py and the benchmark.
 *
 *   ros2_events PERIOD_US LISTENER_US BURN_US[,BURN_US...] [DELAY_US [INTRA_US]]   a job every period,
 *                                                                                   burning those times
 *   ros2_events --fast N                                     N jobs of each, back to back, no burning
 *
 * Times are burnt by spinning on CLOCK_MONOTONIC (LTTng's clock): a job's start-to-end is its burn, and
 * a message's publish-to-take is at least DELAY_US.
 */
#define TRACEPOINT_DEFINE
#define TRACEPOINT_CREATE_PROBES
#include "ros2_tp.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char NODE_T[1], RMW_T[1], NODE_L[1], RMW_L[1], TIMER[1], TIMER_CB[1], PUB[1], RMW_PUB[1], SUB[1],
    RMW_SUB[1], SUB_CPP[1], SUB_CB[1], MESSAGE[1], TAKEN[1], NODE_I[1], RMW_I[1], SUB_I[1], RMW_SUB_I[1],
    SUB_I_CPP[1], SUB_I_CB[1], SUB_I_INTRA[1], SUB_I_INTRA_CB[1], INTRA_MESSAGE[1];

static long long now_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

static void burn_us(long long us) {
  const long long until = now_ns() + us * 1000LL;
  while (now_ns() < until) {
  }
}

static void sleep_until(long long ns) {
  struct timespec t = {(time_t)(ns / 1000000000LL), (long)(ns % 1000000000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, NULL) != 0) {
  }
}

/* a node subscribing /chatter intra-process, registered as rclcpp registers it: the intra-process
 * waitable's callback first, then the subscription's own */
static void intra_registrations(void) {
  const char *symbol = "demo::IntraListener::IntraListener()::{lambda(msg)#1}";
  tracepoint(ros2, rcl_node_init, NODE_I, RMW_I, "intra_listener", "/");
  tracepoint(ros2, rcl_subscription_init, SUB_I, NODE_I, RMW_SUB_I, "/chatter", 10);
  tracepoint(ros2, rclcpp_subscription_callback_added, SUB_I_INTRA, SUB_I_INTRA_CB);
  tracepoint(ros2, rclcpp_callback_register, SUB_I_INTRA_CB, symbol);
  tracepoint(ros2, rclcpp_subscription_init, SUB_I, SUB_I_INTRA);
  tracepoint(ros2, rclcpp_subscription_init, SUB_I, SUB_I_CPP);
  tracepoint(ros2, rclcpp_subscription_callback_added, SUB_I_CPP, SUB_I_CB);
  tracepoint(ros2, rclcpp_callback_register, SUB_I_CB, symbol);
}

static void registrations(long long period_us) {
  tracepoint(ros2, rcl_node_init, NODE_T, RMW_T, "talker", "/");
  tracepoint(ros2, rcl_timer_init, TIMER, period_us * 1000LL);
  tracepoint(ros2, rclcpp_timer_callback_added, TIMER, TIMER_CB);
  tracepoint(ros2, rclcpp_callback_register, TIMER_CB, "demo::Talker::Talker()::{lambda()#1}");
  tracepoint(ros2, rclcpp_timer_link_node, TIMER, NODE_T);
  tracepoint(ros2, rcl_publisher_init, PUB, NODE_T, RMW_PUB, "/chatter", 10);
  tracepoint(ros2, rcl_node_init, NODE_L, RMW_L, "listener", "/");
  tracepoint(ros2, rcl_subscription_init, SUB, NODE_L, RMW_SUB, "/chatter", 10);
  tracepoint(ros2, rclcpp_subscription_init, SUB, SUB_CPP);
  tracepoint(ros2, rclcpp_subscription_callback_added, SUB_CPP, SUB_CB);
  tracepoint(ros2, rclcpp_callback_register, SUB_CB, "demo::Listener::Listener()::{lambda(msg)#1}");
}

/* as DDS stamps a sample: the wall clock, here made strictly increasing (each message its own stamp) */
static long long source_timestamp(void) {
  static long long last;
  struct timespec t;
  clock_gettime(CLOCK_REALTIME, &t);
  const long long now = (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
  last = now > last ? now : last + 1;
  return last;
}

static void job(long long talker_us, long long listener_us, long long delay_us, long long intra_us) {
  tracepoint(ros2, callback_start, TIMER_CB, 0);
  burn_us(talker_us);
  const long long message_timestamp = source_timestamp();
  if (intra_us >= 0) {
    tracepoint(ros2, rclcpp_intra_publish, PUB, INTRA_MESSAGE, (uint64_t)message_timestamp);
  }
  const long long intra_published = now_ns(); /* (after the event: the receipt is at least INTRA_US later) */
  tracepoint(ros2, rcl_publish, PUB, MESSAGE);
  const long long stamp = source_timestamp();
  tracepoint(ros2, rmw_publish, RMW_PUB, MESSAGE, stamp);
  tracepoint(ros2, callback_end, TIMER_CB);
  if (intra_us >= 0) {
    while (now_ns() < intra_published + intra_us * 1000LL) {
    }
    tracepoint(ros2, dispatch_intra_process_subscription_callback, INTRA_MESSAGE, SUB_I_INTRA_CB,
               (uint64_t)message_timestamp);
    tracepoint(ros2, callback_start, SUB_I_INTRA_CB, 1);
    tracepoint(ros2, callback_end, SUB_I_INTRA_CB);
  }
  burn_us(delay_us);
  tracepoint(ros2, rmw_take, RMW_SUB, TAKEN, stamp, 1);
  tracepoint(ros2, callback_start, SUB_CB, 0);
  burn_us(listener_us);
  tracepoint(ros2, callback_end, SUB_CB);
}

int main(int argc, char **argv) {
  if (argc == 3 && strcmp(argv[1], "--fast") == 0) {
    const long long n = atoll(argv[2]);
    registrations(1000);
    for (long long k = 0; k < n; ++k) {
      job(0, 0, 0, -1);
    }
    return 0;
  }
  if (argc < 4 || argc > 6) {
    fprintf(stderr, "usage: ros2_events PERIOD_US LISTENER_US BURN_US[,BURN_US...] [DELAY_US [INTRA_US]] | "
                    "--fast N\n");
    return 2;
  }
  const long long period_us = atoll(argv[1]), listener_us = atoll(argv[2]), delay_us = argc >= 5 ? atoll(argv[4]) : 0;
  const long long intra_us = argc == 6 ? atoll(argv[5]) : -1;
  registrations(period_us);
  if (intra_us >= 0) {
    intra_registrations();
  }
  long long next = now_ns() + period_us * 1000LL;
  for (char *item = strtok(argv[3], ","); item != NULL; item = strtok(NULL, ",")) {
    sleep_until(next);
    job(atoll(item), listener_us, delay_us, intra_us);
    next += period_us * 1000LL;
  }
  return 0;
}
