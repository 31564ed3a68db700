"""``verify trace``: what a robot measured, held against the model (specs/trace.md).

One module per source of measurements, each giving a :class:`recording.Recording` (the callbacks it
saw, identified as CARET identifies them, and their jobs): ``lttng`` (LTTng/CTF traces as
ros2_tracing and CARET record them, read with babeltrace2's Python bindings; ``links`` links their
messages from publish to receipt) and ``jobrecords`` (the job records of the generated ROS 1 and ROS 2
nodes). ``match`` pairs recorded callbacks with the model's tasks, ``metrics`` measures tasks and chains,
``delays`` the connections, ``findings`` turns measurements above the model into located diagnostics,
``calibrate`` writes measured execution times and delays into the model (``standin`` stands in for a
model that lacks wcets, priorities or cores).
"""
