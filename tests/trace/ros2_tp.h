/* Tracepoints of the `ros2` provider with the names, fields and field types ros2_tracing's
 * tracetools defines (tracetools/tp_call.h; rmw_publish with its source `timestamp`, as since Jazzy), and
 * CARET's for intra-process messages (its fork of tracetools: rclcpp_intra_publish with the
 * `message_timestamp`, dispatch_intra_process_subscription_callback), for tests/ros2_events.c: the events
 * `verify trace` reads. */
#undef TRACEPOINT_PROVIDER
#define TRACEPOINT_PROVIDER ros2

#undef TRACEPOINT_INCLUDE
#define TRACEPOINT_INCLUDE "./ros2_tp.h"

#if !defined(ROS2_TP_H) || defined(TRACEPOINT_HEADER_MULTI_READ)
#define ROS2_TP_H

#include <lttng/tracepoint.h>
#include <stddef.h>
#include <stdint.h>

TRACEPOINT_EVENT(ros2, rcl_node_init,
  TP_ARGS(const void *, node_handle_arg, const void *, rmw_handle_arg, const char *, node_name_arg,
          const char *, namespace_arg),
  TP_FIELDS(ctf_integer_hex(const void *, node_handle, node_handle_arg)
            ctf_integer_hex(const void *, rmw_handle, rmw_handle_arg)
            ctf_string(node_name, node_name_arg)
            ctf_string(namespace, namespace_arg)))

TRACEPOINT_EVENT(ros2, rcl_publisher_init,
  TP_ARGS(const void *, publisher_handle_arg, const void *, node_handle_arg, const void *, rmw_publisher_handle_arg,
          const char *, topic_name_arg, const size_t, queue_depth_arg),
  TP_FIELDS(ctf_integer_hex(const void *, publisher_handle, publisher_handle_arg)
            ctf_integer_hex(const void *, node_handle, node_handle_arg)
            ctf_integer_hex(const void *, rmw_publisher_handle, rmw_publisher_handle_arg)
            ctf_string(topic_name, topic_name_arg)
            ctf_integer(const size_t, queue_depth, queue_depth_arg)))

TRACEPOINT_EVENT(ros2, rcl_subscription_init,
  TP_ARGS(const void *, subscription_handle_arg, const void *, node_handle_arg,
          const void *, rmw_subscription_handle_arg, const char *, topic_name_arg, const size_t, queue_depth_arg),
  TP_FIELDS(ctf_integer_hex(const void *, subscription_handle, subscription_handle_arg)
            ctf_integer_hex(const void *, node_handle, node_handle_arg)
            ctf_integer_hex(const void *, rmw_subscription_handle, rmw_subscription_handle_arg)
            ctf_string(topic_name, topic_name_arg)
            ctf_integer(const size_t, queue_depth, queue_depth_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_subscription_init,
  TP_ARGS(const void *, subscription_handle_arg, const void *, subscription_arg),
  TP_FIELDS(ctf_integer_hex(const void *, subscription_handle, subscription_handle_arg)
            ctf_integer_hex(const void *, subscription, subscription_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_subscription_callback_added,
  TP_ARGS(const void *, subscription_arg, const void *, callback_arg),
  TP_FIELDS(ctf_integer_hex(const void *, subscription, subscription_arg)
            ctf_integer_hex(const void *, callback, callback_arg)))

TRACEPOINT_EVENT(ros2, rcl_timer_init,
  TP_ARGS(const void *, timer_handle_arg, int64_t, period_arg),
  TP_FIELDS(ctf_integer_hex(const void *, timer_handle, timer_handle_arg)
            ctf_integer(int64_t, period, period_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_timer_callback_added,
  TP_ARGS(const void *, timer_handle_arg, const void *, callback_arg),
  TP_FIELDS(ctf_integer_hex(const void *, timer_handle, timer_handle_arg)
            ctf_integer_hex(const void *, callback, callback_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_timer_link_node,
  TP_ARGS(const void *, timer_handle_arg, const void *, node_handle_arg),
  TP_FIELDS(ctf_integer_hex(const void *, timer_handle, timer_handle_arg)
            ctf_integer_hex(const void *, node_handle, node_handle_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_callback_register,
  TP_ARGS(const void *, callback_arg, const char *, symbol_arg),
  TP_FIELDS(ctf_integer_hex(const void *, callback, callback_arg)
            ctf_string(symbol, symbol_arg)))

TRACEPOINT_EVENT(ros2, callback_start,
  TP_ARGS(const void *, callback_arg, const int, is_intra_process_arg),
  TP_FIELDS(ctf_integer_hex(const void *, callback, callback_arg)
            ctf_integer(const int, is_intra_process, is_intra_process_arg)))

TRACEPOINT_EVENT(ros2, callback_end,
  TP_ARGS(const void *, callback_arg),
  TP_FIELDS(ctf_integer_hex(const void *, callback, callback_arg)))

TRACEPOINT_EVENT(ros2, rcl_publish,
  TP_ARGS(const void *, publisher_handle_arg, const void *, message_arg),
  TP_FIELDS(ctf_integer_hex(const void *, publisher_handle, publisher_handle_arg)
            ctf_integer_hex(const void *, message, message_arg)))

TRACEPOINT_EVENT(ros2, rmw_publish,
  TP_ARGS(const void *, rmw_publisher_handle_arg, const void *, message_arg, int64_t, timestamp_arg),
  TP_FIELDS(ctf_integer_hex(const void *, rmw_publisher_handle, rmw_publisher_handle_arg)
            ctf_integer_hex(const void *, message, message_arg)
            ctf_integer(int64_t, timestamp, timestamp_arg)))

TRACEPOINT_EVENT(ros2, rmw_take,
  TP_ARGS(const void *, rmw_subscription_handle_arg, const void *, message_arg, int64_t, source_timestamp_arg,
          const int, taken_arg),
  TP_FIELDS(ctf_integer_hex(const void *, rmw_subscription_handle, rmw_subscription_handle_arg)
            ctf_integer_hex(const void *, message, message_arg)
            ctf_integer(int64_t, source_timestamp, source_timestamp_arg)
            ctf_integer(const int, taken, taken_arg)))

TRACEPOINT_EVENT(ros2, rclcpp_intra_publish,
  TP_ARGS(const void *, publisher_handle_arg, const void *, message_arg, const uint64_t, message_timestamp_arg),
  TP_FIELDS(ctf_integer_hex(const void *, publisher_handle, publisher_handle_arg)
            ctf_integer_hex(const void *, message, message_arg)
            ctf_integer(const uint64_t, message_timestamp, message_timestamp_arg)))

TRACEPOINT_EVENT(ros2, dispatch_intra_process_subscription_callback,
  TP_ARGS(const void *, message_arg, const void *, callback_arg, const uint64_t, message_timestamp_arg),
  TP_FIELDS(ctf_integer_hex(const void *, message, message_arg)
            ctf_integer_hex(const void *, callback, callback_arg)
            ctf_integer(const uint64_t, message_timestamp, message_timestamp_arg)))

#endif /* ROS2_TP_H */

#include <lttng/tracepoint-event.h>
