"""Records what the generated nodes publish, for tests/test_gen_ros1.py (run by Debian's python3,
which has rospy): every job record (/verify/jobs), every violation (/verify/violations) and the raw
bytes of every data message on the topics given, one JSON object per line in OUT.

    /usr/bin/python3 tests/ros/record.py OUT TOPIC...
"""
import json
import sys
import threading

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
        else:
            item["data"] = message.data
        with lock:
            out.write(json.dumps(item) + "\n")
    return record


rospy.init_node("verify_test_recorder", anonymous=True)
rospy.Subscriber("/verify/jobs", String, recorder("/verify/jobs", False), queue_size=100000)
rospy.Subscriber("/verify/violations", String, recorder("/verify/violations", False), queue_size=100000)
for name in sys.argv[2:]:
    rospy.Subscriber(name, rospy.AnyMsg, recorder(name, True), queue_size=100000)
with lock:
    out.write(json.dumps({"topic": "ready"}) + "\n")
rospy.spin()
