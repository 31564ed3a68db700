"""Records what the generated nodes publish, for tests/test_gen_ros1_live.py (run by Debian's python3,
which has rospy): every job record (/verify/jobs), every violation (/verify/violations) and, for each
topic given, the raw bytes of every message with the type its publisher declared; one JSON object per
line in OUT. A topic given as TOPIC=PACKAGE/TYPE is subscribed as that type (a stock subscriber: ROS
connects it only if the publisher's type and checksum are the same) and recorded as "typed".

    /usr/bin/python3 tests/ros/record.py OUT TOPIC[=PACKAGE/TYPE]...
"""
import json
import sys
import threading

import roslib.message
import rospy
from std_msgs.msg import String

lock = threading.Lock()
out = open(sys.argv[1], "w", buffering=1, encoding="utf-8")  # noqa: SIM115 (open while rospy spins)


def recorder(topic, raw):
    def record(message):
        stamp = rospy.Time.now().to_nsec()
        item = {"topic": topic, "received": stamp}
        if raw:
            item["hex"] = message._buff.hex()
            item["type"] = message._connection_header["type"]
            item["publisher"] = message._connection_header["callerid"]
        elif raw is None:
            item["typed"] = message._type
        else:
            item["data"] = message.data
        with lock:
            out.write(json.dumps(item) + "\n")
    return record


rospy.init_node("verify_test_recorder", anonymous=True)
rospy.Subscriber("/verify/jobs", String, recorder("/verify/jobs", False), queue_size=100000)
rospy.Subscriber("/verify/violations", String, recorder("/verify/violations", False), queue_size=100000)
for name in sys.argv[2:]:
    if "=" in name:
        topic, kind = name.split("=", 1)
        rospy.Subscriber(topic, roslib.message.get_message_class(kind), recorder(topic, None), queue_size=100000)
    else:
        rospy.Subscriber(name, rospy.AnyMsg, recorder(name, True), queue_size=100000)
with lock:
    out.write(json.dumps({"topic": "ready"}) + "\n")
rospy.spin()
