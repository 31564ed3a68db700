"""The runtime of the ROS 2 nodes `verify gen ros2` writes (specs/codegen.md §9; the generated
package's ``verify_ros2/__init__.py``): what the functional code sees (``component``), chain monitors
(``monitor``), the wire (``wire``), the order of jobs (``dispatch``), one process (``unit``) and the
runner (``run``)."""
from .component import Component, Input, Output, burn

__all__ = ["Component", "Input", "Output", "burn"]
