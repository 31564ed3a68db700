"""``verify gen ros1``: ROS 1 (roscpp) nodes that run a configured system as specs/timing.md defines it.

The mapping from each model construct to code, and what the generated code guarantees, is
specs/codegen.md. The layout of the generated project:

    CMakeLists.txt, package.xml            glue: plain CMake against Debian's roscpp, std_msgs and the
                                           packages of the ROS messages the message types are bound to
    include/verify_ros1/*.hpp              glue: the runtime and monitor library (verify/gen/ros1_runtime)
    glue/<Component>.hpp, <Component>_main.cpp
                                           glue: per component, its base class and its node's main
    config/parameters.yaml                 glue: every period, phase, prescaler, priority, CPU, topic and
                                           chain role; the only file a changed configuration changes
    launch/<system>.launch                 glue: starts one node per instance
    user/<Component>.hpp                   user: the class with the component's functional code
    user/types/<Type>.hpp                  user: the C++ type of a message type (its ROS message, if bound)
    user/user.cmake                        user: extra packages and libraries for the user's code
"""
from __future__ import annotations

import re
from collections.abc import Callable
from fractions import Fraction
from importlib import resources

from ..model.system import ComponentModel, MessageModel, SystemModel, TaskDecl, TaskModel
from ..core.sanitize import c_string, comment, yaml_string
from ..core.source import Span
from .tree import File, Tree, stamped

TARGET = "ros1"
HELP = "ROS 1 (roscpp) nodes, parameters and a launch file, built with plain CMake"
GENERATOR = "verify gen ros1"

#: names a C++ identifier must not take (keywords and alternative tokens, lower-case macros of the C
#: library, POSIX and the headers the glue includes — ``g++ -dM -E`` of runtime.hpp on Debian 12 —,
#: the namespaces the glue refers to, and ``main``); ``_`` is appended (``cpp``)
_RESERVED = frozenset((
    "alignas", "alignof", "and", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "break", "case", "catch",
    "char", "char8_t", "char16_t", "char32_t", "class", "compl", "concept", "const", "consteval", "constexpr",
    "constinit", "const_cast", "continue", "co_await", "co_return", "co_yield", "decltype", "default", "delete",
    "do", "double", "dynamic_cast", "else", "enum", "explicit", "export", "extern", "false", "float", "for",
    "friend", "goto", "if", "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not", "not_eq",
    "nullptr", "operator", "or", "or_eq", "private", "protected", "public", "register", "reinterpret_cast",
    "requires", "return", "short", "signed", "sizeof", "static", "static_assert", "static_cast", "struct",
    "switch", "template", "this", "thread_local", "throw", "true", "try", "typedef", "typeid", "typename",
    "union", "unsigned", "using", "virtual", "void", "volatile", "wchar_t", "while", "xor", "xor_eq", "NULL",
    "EOF", "errno", "assert", "major", "minor", "stdin", "stdout", "stderr", "unix", "linux", "main",
    # lower-case macros of glibc and POSIX (upper-case ones: ``macro_like``)
    "alloca", "assert_perror", "be16toh", "be32toh", "be64toh", "htobe16", "htobe32", "htobe64", "htole16",
    "htole32", "htole64", "le16toh", "le32toh", "le64toh", "htonl", "htons", "ntohl", "ntohs", "issubnormal",
    "math_errhandling", "offsetof", "pthread_cleanup_pop", "pthread_cleanup_pop_restore_np",
    "pthread_cleanup_push", "pthread_cleanup_push_defer_np", "sa_handler", "sa_sigaction", "sched_priority",
    "si_addr", "si_addr_lsb", "si_arch", "si_band", "si_call_addr", "si_fd", "si_int", "si_lower", "si_overrun",
    "si_pid", "si_pkey", "si_ptr", "si_status", "si_stime", "si_syscall", "si_timerid", "si_uid", "si_upper",
    "si_utime", "si_value", "sigev_notify_attributes", "sigev_notify_function", "sigmask", "strdupa", "strndupa",
    "timeradd", "timerclear", "timercmp", "timerisset", "timersub", "va_arg", "va_copy", "va_end", "va_start",
    "setjmp", "st_atime", "st_mtime", "st_ctime", "i386",
    # the namespaces the generated code and its runtime name (a class of that name would hide them)
    "glue", "msg", "ros", "std", "boost", "verify_gen", "verify_ros1", "std_msgs", "XmlRpc",
))

#: the keys beside the instances in the parameters of a system (an instance of that name is renamed)
_SYSTEM_KEYS = frozenset(("nodes",))

#: SCHED_FIFO priorities of the tasks: the model's priorities in order, spread over this range
#: (the middleware's threads run above it, at 97; the timers at 98)
OS_PRIORITY_LOW, OS_PRIORITY_HIGH = 10, 90


def macro_like(name: str) -> bool:
    """Whether ``name`` is spelt as macros are (C++ Core Guidelines ES.9): two characters or more, and
    no lower-case letter before its first underscore (``SIGINT``, ``NULL``, ``EOF``, ``ROS_INFO``,
    ``M_PIf``, ``IMU``)."""
    head = name.split("_", 1)[0]
    return len(name) >= 2 and any(c.isupper() for c in head) and not any(c.islower() for c in head)


def cpp(name: str) -> str:
    """``name`` as a C++ identifier: a reserved word or a macro's name (``_RESERVED``, ``macro_like``),
    or a name C++ reserves (a leading underscore, a double one), gets a trailing ``_``. Two names that
    become one are refused before anything is generated (``clashes``, E603)."""
    if name in _RESERVED or name.startswith("_") or "__" in name or macro_like(name):
        return name + "_"
    return name


def ros_name(name: str) -> str:
    """``name`` as a ROS graph name (which must start with a letter); ``nodes``, the key of the list
    of a system's nodes in the parameters, gets a trailing ``_``."""
    name = name if name[:1].isalpha() else "n" + name
    return name + "_" if name in _SYSTEM_KEYS else name


def package_name(system: str) -> str:
    """The ROS package of the generated nodes: ``NavigationHoles`` → ``navigation_holes_nodes``."""
    snake = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", system).lower().strip("_")
    snake = re.sub(r"_+", "_", snake)
    return f"{snake if snake[:1].isalpha() else 'n' + snake}_nodes"


def nanoseconds(seconds: Fraction) -> str:
    """An exact time as the runtime reads it: ns, ``"N"`` or ``"N/D"``."""
    ns = seconds * 1_000_000_000
    return str(ns.numerator) if ns.denominator == 1 else f"{ns.numerator}/{ns.denominator}"


def human(seconds: Fraction) -> str:
    """A time for a comment: ``25 ms``, ``1/30 s``."""
    for unit, factor in (("s", 1), ("ms", 1000), ("us", 1_000_000), ("ns", 1_000_000_000)):
        value = seconds * factor
        if value.denominator == 1 and (value >= 1 or unit == "ns"):
            return f"{value.numerator} {unit}"
    return f"{seconds.numerator}/{seconds.denominator} s"


# ------------------------------------------------------------------ the tree


def unsupported(model: SystemModel) -> list[tuple[Span, str, str]]:
    """What ROS 1 cannot run as verified: an executor of ROS 2 (specs/timing.md §9) — roscpp's spinners
    are not rclcpp's executors, and a node's callbacks here are threads of their own."""
    return [(ex.span, f"executor `{ex.name}` is a ROS 2 executor, which the ros1 target cannot run",
             "bind its callbacks with a priority and a core (each becomes a thread of the generated node), "
             "or keep the executor for the analysis and write its ROS 2 code yourself")
            for ex in model.executors]


def clashes(model: SystemModel) -> list[tuple[Span, Span, str]]:
    """Names the generated code would make one (E603): (the later declaration, the earlier one, what
    clashes). Components (classes, headers, executables) and message types (aliases, headers) are
    compared case-insensitively, as a file system may compare file names; the ports of a component
    (the parameters of its ``on_TASK``) and the instances (nodes, keys of the parameters) exactly."""
    types: dict[str, Span] = {}
    for comp in model.components:
        for port in comp.ports:
            types.setdefault(port.message_type, port.span)
    found = _clashes_among("component", [(c.name, c.span) for c in model.components], cpp, fold=True)
    found += _clashes_among("message type", list(types.items()), cpp, fold=True)
    for comp in model.components:
        found += _clashes_among(f"component `{comp.name}`'s port", [(p.name, p.span) for p in comp.ports], cpp)
    found += _clashes_among("instance", [(i.name, i.span) for i in model.instances], ros_name)
    return found


def _clashes_among(kind: str, names: list[tuple[str, Span]], made: Callable[[str], str],
                   fold: bool = False) -> list[tuple[Span, Span, str]]:
    seen: dict[str, tuple[str, Span]] = {}
    found = []
    for name, span in names:
        key = made(name).casefold() if fold else made(name)
        if key not in seen:
            seen[key] = (name, span)
            continue
        first, first_span = seen[key]
        if made(first) == made(name):
            how = f"as {kind} `{first}` does"
        else:
            how = f"which a case-insensitive file system takes for `{made(first)}`, {kind} `{first}`'s"
        found.append((span, first_span, f"{kind} `{name}` becomes `{made(name)}` in the generated code, {how}"))
    return found


def generate(model: SystemModel) -> Tree:
    """The project of a configured system (no synthesis holes: the command checks that first)."""
    pkg = package_name(model.name)
    files = [File(f"include/verify_ros1/{name}", _runtime(name), "glue")
             for name in ("envelope.hpp", "monitor.hpp", "runtime.hpp")]
    messages = {m.name: m for m in model.messages}
    files += [File("CMakeLists.txt", _cmake(model, pkg), "glue"), File("package.xml", _package_xml(model, pkg), "glue"),
              File("config/parameters.yaml", _parameters(model), "glue"),
              File(f"launch/{ros_name(model.name)}.launch", _launch(model, pkg), "glue")]
    for comp in model.components:
        files.append(File(f"glue/{cpp(comp.name)}.hpp", _glue_class(comp, messages), "glue"))
        files.append(File(f"glue/{cpp(comp.name)}_main.cpp", _main(comp), "glue"))
    for comp in model.components:
        files.append(File(f"user/{cpp(comp.name)}.hpp", _skeleton(comp), "user"))
    for type_name in sorted({p.message_type for c in model.components for p in c.ports}):
        files.append(File(f"user/types/{cpp(type_name)}.hpp", _type_header(type_name, messages.get(type_name)),
                          "user"))
    files.append(File("user/user.cmake", _user_cmake(), "user"))
    return Tree(tuple(File(f.path, stamped(f.path, f.text, GENERATOR), "glue") if f.owner == "glue" else f
                      for f in files))


def _runtime(name: str) -> str:
    return resources.files("verify.gen").joinpath("ros1_runtime", "verify_ros1", name).read_text(encoding="utf-8")


# ------------------------------------------------------------------ C++: glue per component


def _type(type_name: str) -> str:
    return f"msg::{cpp(type_name)}"


def ros_cpp(message: MessageModel) -> str:
    """The C++ class of a ROS 1 message: ``::sensor_msgs::LaserScan`` (qualified: a component may be named
    as a package is)."""
    return f"::{message.package}::{message.type}"


def _wire(type_name: str, messages: dict[str, MessageModel]) -> str:
    """What a message type travels as (specs/codegen.md §6): its ROS message, or bytes when unbound."""
    message = messages.get(type_name)
    return ros_cpp(message) if message is not None else "verify_ros1::Bytes"


def _port_type(kind: str, type_name: str, messages: dict[str, MessageModel]) -> str:
    return f"verify_ros1::{kind}<{_type(type_name)}, {_wire(type_name, messages)}>"


def _signature(comp: ComponentModel, task: TaskDecl, override: bool) -> str:
    """The parameters of ``on_TASK``: each input, then each output."""
    params = []
    for r in task.reads:
        port = comp.port(r.port)
        assert port is not None
        attr = "[[maybe_unused]] " if override else ""
        params.append(f"{attr}const verify_ros1::Input<{_type(port.message_type)}>& {cpp(r.port)}")
    for name in task.produces:
        port = comp.port(name)
        assert port is not None
        attr = "[[maybe_unused]] " if override else ""
        params.append(f"{attr}{_type(port.message_type)}& {cpp(name)}")
    return ", ".join(params)


def _task_comment(task: TaskDecl) -> str:
    reads = ", ".join(r.port + (" (optional)" if r.optional else "") for r in task.reads) or "nothing"
    produces = ", ".join(task.produces) or "nothing"
    wcet = human(task.wcet) if task.wcet is not None else "?"
    return (f"{task.name} ({task.kind}): reads {reads}; produces {produces}; "
            f"execution time {human(task.bcet)} .. {wcet}")


def _job_method(comp: ComponentModel, task: TaskDecl) -> list[str]:
    """The job of ``task``: read every input at the start, run the user's code, write at completion."""
    lines = [f"  void job_{task.name}(verify_ros1::Job& job) {{"]
    for r in task.reads:
        port = comp.port(r.port)
        assert port is not None
        lines.append(f"    verify_ros1::Input<{_type(port.message_type)}> in_{r.port};")
    lines.append("    {")
    lines.append("      std::lock_guard<std::mutex> lock(registers());")
    lines.append("      job.start = verify_ros1::now_ns();")
    lines.append("      job.cpu_start = verify_ros1::thread_cpu_ns();")
    lines += [f"      port_{r.port}_.read(in_{r.port}, job);" for r in task.reads]
    lines.append("    }")
    lines.append("    job.hold();")
    for name in task.produces:
        port = comp.port(name)
        assert port is not None
        lines.append(f"    {_type(port.message_type)} out_{name}{{}};")
    args = [f"in_{r.port}" for r in task.reads] + [f"out_{p}" for p in task.produces]
    lines.append(f"    on_{task.name}({', '.join(args)});")
    lines.append("    job.cpu = verify_ros1::thread_cpu_ns() - job.cpu_start;")
    lines.append("    job.finish = verify_ros1::now_ns();")
    lines += [f"    port_{p}_.write(out_{p}, job);" for p in task.produces]
    lines.append("  }")
    return lines


def _includes(comp: ComponentModel) -> list[str]:
    return [f'#include "types/{cpp(t)}.hpp"' for t in sorted({p.message_type for p in comp.ports})]


def _message_includes(comp: ComponentModel, messages: dict[str, MessageModel]) -> list[str]:
    """The headers of the ROS messages the component's bound types are (the glue names them itself)."""
    bound = {messages[p.message_type] for p in comp.ports if p.message_type in messages}
    return sorted(f"#include <{m.package}/{m.type}.h>" for m in bound)


def _bound_checks(comp: ComponentModel, messages: dict[str, MessageModel]) -> list[str]:
    """A compile-time check per bound type: its user header (written once) still names its ROS message."""
    lines = []
    for type_name in sorted({p.message_type for p in comp.ports if p.message_type in messages}):
        message = messages[type_name]
        lines.append(f"static_assert(std::is_same<verify_gen::{_type(type_name)}, {ros_cpp(message)}>::value,")
        lines.append(f'              "message type {c_string(type_name)[1:-1]} is bound to {message.ros1} in the '
                     f'model: user/types/{cpp(type_name)}.hpp must name it (delete the file and regenerate)");')
    return lines


def _glue_class(comp: ComponentModel, messages: dict[str, MessageModel]) -> str:
    name = cpp(comp.name)
    lines = ["// The glue of component " + comment(comp.name) + ": its ports, compound in-ports and tasks, with the",
             "// activation and communication semantics of specs/timing.md (specs/codegen.md). The functional",
             f"// code is the user's, in user/{name}.hpp.",
             "#pragma once", "", "#include <mutex>", "#include <utility>", "",
             '#include "verify_ros1/runtime.hpp"', *_message_includes(comp, messages), *_includes(comp), "",
             *(_bound_checks(comp, messages) + [""] if _bound_checks(comp, messages) else []),
             "namespace verify_gen {", "namespace glue {", "",
             f"class {name} : public verify_ros1::Component {{", " public:",
             f"  {name}(ros::NodeHandle nh, ros::NodeHandle pnh)",
             f"      : verify_ros1::Component(std::move(nh), std::move(pnh), {c_string(comp.name)}) {{"]
    lines += [f"    subscribe(port_{p.name}_);" for p in comp.in_ports]
    lines += [f"    advertise(port_{p.name}_);" for p in comp.out_ports]
    for c in comp.compounds:
        members = ", ".join(c_string(m) for m in c.members)
        mode = "true" if c.mode == "and" else "false"
        lines.append(f"    declare_compound({c_string(c.name)}, {mode}, {{{members}}});")
    for t in comp.tasks:
        coop = "true" if t.kind == "cooperative" else "false"
        lines.append(f"    declare_task({c_string(t.name)}, {coop}, "
                     f"[this](verify_ros1::Job& job) {{ job_{t.name}(job); }});")
    lines += ["  }", "", " protected:"]
    for t in comp.tasks:
        lines.append(f"  // {comment(_task_comment(t))}")
        lines.append(f"  virtual void on_{t.name}({_signature(comp, t, False)}) = 0;")
    lines += ["", " private:"]
    for t in comp.tasks:
        lines += _job_method(comp, t)
    for p in comp.in_ports:
        lines.append(f"  {_port_type('InPort', p.message_type, messages)} port_{p.name}_{{{c_string(p.name)}}};")
    for p in comp.out_ports:
        lines.append(f"  {_port_type('OutPort', p.message_type, messages)} port_{p.name}_{{{c_string(p.name)}}};")
    lines += ["};", "", "}  // namespace glue", "}  // namespace verify_gen", ""]
    return "\n".join(lines)


def _main(comp: ComponentModel) -> str:
    name = cpp(comp.name)
    return "\n".join([f"// The node of component {comment(comp.name)}: one process per instance (launch/*.launch).",
                      f'#include "user/{name}.hpp"', "",
                      "int main(int argc, char** argv) {",
                      f"  return verify_ros1::main_of<verify_gen::{name}>(argc, argv, {c_string(comp.name.lower())});",
                      "}", ""])


# ------------------------------------------------------------------ C++: the user's files (written once)


def _skeleton(comp: ComponentModel) -> str:
    name, title = cpp(comp.name), comment(comp.name)
    lines = [f"// Component {title}: your functional code. `verify gen ros1` wrote this file once and never",
             "// overwrites it; the glue it builds on (glue/" + name + ".hpp) is regenerated. Each on_TASK runs",
             "// one job: its inputs are the values read when the job started (`in.has_value()`: whether one",
             "// has arrived), its outputs are published when it returns.",
             "#pragma once", "", f'#include "glue/{name}.hpp"', "", "namespace verify_gen {", "",
             f"class {name} : public glue::{name} {{", " public:", f"  using glue::{name}::{name};", "",
             " protected:"]
    for t in comp.tasks:
        lines.append(f"  // {comment(_task_comment(t))}")
        lines.append(f"  void on_{t.name}({_signature(comp, t, True)}) override {{")
        lines.append("  }")
    lines += ["};", "", "}  // namespace verify_gen", ""]
    return "\n".join(lines)


def _type_header(type_name: str, message: MessageModel | None) -> str:
    if message is not None:
        return "\n".join([
            f"// The C++ type of message type {comment(type_name)}: the ROS message {message.ros1}, as the model binds",
            "// it (`message ... = ros ...`). `verify gen ros1` wrote this file once and never overwrites it; the",
            "// glue checks at compile time that it still names that message.",
            "#pragma once", "", f"#include <{message.package}/{message.type}.h>", "",
            "namespace verify_gen {", "namespace msg {", "",
            f"using {cpp(type_name)} = {ros_cpp(message)};", "",
            "}  // namespace msg", "}  // namespace verify_gen", ""])
    return "\n".join([
        f"// The C++ type of message type {comment(type_name)}. `verify gen ros1` wrote this file once and never",
        "// overwrites it: make it any type ros::serialization can serialize, or keep the bytes. On the wire",
        "// it is bytes (std_msgs/UInt8MultiArray); to send a ROS message that other ROS nodes understand,",
        "// bind the type in the model (`message T = ros \"sensor_msgs/LaserScan\"`) and regenerate.",
        "#pragma once", "", "#include <cstdint>", "#include <vector>", "",
        "namespace verify_gen {", "namespace msg {", "",
        f"using {cpp(type_name)} = std::vector<std::uint8_t>;", "",
        "}  // namespace msg", "}  // namespace verify_gen", ""])


def _user_cmake() -> str:
    return "\n".join([
        "# Your additions to the build (included by CMakeLists.txt; written once, never overwritten):",
        "# packages your functional code needs, and their include directories and libraries, e.g.",
        "#   find_package(sensor_msgs REQUIRED)",
        "#   list(APPEND VERIFY_USER_INCLUDE_DIRS ${sensor_msgs_INCLUDE_DIRS})",
        "#   list(APPEND VERIFY_USER_LIBRARIES ${sensor_msgs_LIBRARIES})", ""])


# ------------------------------------------------------------------ build and launch


def _cmake(model: SystemModel, pkg: str) -> str:
    lines = ["cmake_minimum_required(VERSION 3.16)", f"project({pkg} CXX)", "",
             "set(CMAKE_CXX_STANDARD 17)", "set(CMAKE_CXX_STANDARD_REQUIRED ON)",
             "if(NOT CMAKE_BUILD_TYPE)", "  set(CMAKE_BUILD_TYPE RelWithDebInfo)", "endif()", "",
             "find_package(roscpp REQUIRED)", "find_package(std_msgs REQUIRED)", "find_package(Threads REQUIRED)",
             *_message_headers(model),
             "", "set(VERIFY_USER_INCLUDE_DIRS)", "set(VERIFY_USER_LIBRARIES)",
             "include(${CMAKE_CURRENT_SOURCE_DIR}/user/user.cmake OPTIONAL)", "",
             "function(verify_node name main)", "  add_executable(${name} ${main})",
             "  target_compile_options(${name} PRIVATE -Wall -Wextra)",
             "  target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/include",
             "                             ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/user)",
             "  target_include_directories(${name} SYSTEM PRIVATE ${roscpp_INCLUDE_DIRS} ${std_msgs_INCLUDE_DIRS}",
             *(f"                             ${{VERIFY_MSG_{p}}}" for p in _packages(model)),
             "                             ${VERIFY_USER_INCLUDE_DIRS})",
             "  target_link_libraries(${name} PRIVATE ${roscpp_LIBRARIES} ${VERIFY_USER_LIBRARIES} Threads::Threads)",
             "endfunction()", ""]
    lines += [f"verify_node({cpp(c.name)}_node glue/{cpp(c.name)}_main.cpp)" for c in model.components]
    return "\n".join(lines) + "\n"


def _message_headers(model: SystemModel) -> list[str]:
    """Where the headers of the bound messages are: ROS 1 messages are header-only (their packages'
    CMake configurations need catkin, which a plain CMake build has not), one header per package found."""
    first: dict[str, str] = {}
    for m in model.messages:
        first.setdefault(m.package, m.type)
    lines = ["# the bound message types' ROS messages (header-only)"] if first else []
    for package in _packages(model):
        lines.append(f"find_path(VERIFY_MSG_{package} {package}/{first[package]}.h REQUIRED)")
    return lines


def _packages(model: SystemModel) -> list[str]:
    """The ROS packages of the messages the system's message types are bound to (std_msgs is always used)."""
    return sorted({m.package for m in model.messages} - {"std_msgs", "roscpp"})


def _package_xml(model: SystemModel, pkg: str) -> str:
    return "\n".join([
        '<package format="2">', f"  <name>{pkg}</name>", "  <version>0.0.0</version>",
        f"  <description>The nodes of system {model.name}, generated by {GENERATOR}.</description>",
        '  <maintainer email="nobody@example.org">nobody</maintainer>', "  <license>MIT</license>",
        "  <buildtool_depend>cmake</buildtool_depend>", "  <depend>roscpp</depend>", "  <depend>std_msgs</depend>",
        *(f"  <depend>{p}</depend>" for p in _packages(model)), "</package>", ""])


def _launch(model: SystemModel, pkg: str) -> str:
    ns = ros_name(model.name)
    lines = ["<launch>",
             "  <!-- trace: every job is published on /verify/jobs; monitor: chain stamps and latency monitors;",
             "       summary_dir: where each node writes its monitors' summary at shutdown (\"\": nowhere) -->",
             '  <arg name="trace" default="false"/>', '  <arg name="monitor" default="true"/>',
             '  <arg name="summary_dir" default=""/>',
             '  <param name="/verify/trace" value="$(arg trace)"/>',
             '  <param name="/verify/monitor" value="$(arg monitor)"/>',
             '  <param name="/verify/summary_dir" value="$(arg summary_dir)"/>',
             '  <param name="/verify/run" value="$(anon run)"/>  <!-- the nodes of this launch start together -->',
             '  <rosparam command="load" file="$(dirname)/../config/parameters.yaml"/>',
             f'  <group ns="{ns}">']
    for inst in model.instances:
        lines.append(f'    <node pkg="{pkg}" type="{cpp(inst.component)}_node" name="{ros_name(inst.name)}" '
                     'output="screen"/>')
    lines += ["  </group>", "</launch>", ""]
    return "\n".join(lines)


# ------------------------------------------------------------------ parameters


def os_priorities(model: SystemModel) -> dict[int, int]:
    """The SCHED_FIFO priority of each model priority: their order kept, equal ones equal, spread
    over [OS_PRIORITY_LOW, OS_PRIORITY_HIGH]."""
    levels = sorted({t.priority for t in model.tasks})
    if len(levels) == 1:
        return {levels[0]: OS_PRIORITY_LOW}
    span = OS_PRIORITY_HIGH - OS_PRIORITY_LOW
    if len(levels) > span + 1:  # more levels than SCHED_FIFO has: ranks, clipped (specs/codegen.md)
        return {p: min(OS_PRIORITY_LOW + i, OS_PRIORITY_HIGH) for i, p in enumerate(levels)}
    return {p: OS_PRIORITY_LOW + (i * span) // (len(levels) - 1) for i, p in enumerate(levels)}


def chain_roles(model: SystemModel) -> dict[str, list[dict[str, object]]]:
    """Per task id, the part it plays in each chain (specs/codegen.md, "Chain stamps")."""
    roles: dict[str, list[dict[str, object]]] = {}
    for index, chain in enumerate(model.chains):
        n = len(chain.tasks)
        for i, task in enumerate(chain.tasks):
            role: dict[str, object] = {"chain": index, "name": chain.name, "position": i,
                                       "from": chain.hops[i - 1].link.target.split(".", 1)[1] if i > 0 else "",
                                       "to": chain.hops[i].link.source.split(".", 1)[1] if i < n - 1 else ""}
            if i == n - 1:
                for kind, bound in (("reaction_time", chain.reaction_time), ("data_age", chain.data_age),
                                    ("jitter", chain.jitter)):
                    if bound is not None:
                        role[f"{kind}_ns"] = nanoseconds(bound)
            roles.setdefault(task, []).append(role)
    return roles


def _activation(task: TaskModel) -> list[str]:
    # (the glue's activation kinds: a timer, a data trigger, or a source released between two gaps)
    act = task.activation
    period, port, gaps = act.strict_period, act.trigger_port, act.gaps
    if period is not None:
        lines = ['activation: "timer"', f"period_ns: {yaml_string(nanoseconds(period))}  # {human(period)}"]
        phase = act.fixed_phase
        if phase is not None:
            lines.append(f"phase_ns: {yaml_string(nanoseconds(phase))}")
        return lines
    if port is not None:
        return ['activation: "trigger"', f"trigger: {yaml_string(port)}", f"prescaler: {act.release_every}"]
    assert gaps is not None  # (a hole never reaches code generation)
    return ['activation: "sporadic"', f"min_ns: {yaml_string(nanoseconds(gaps[0]))}",
            f"max_ns: {yaml_string(nanoseconds(gaps[1]))}"]


def _yaml_scalar(value: object) -> str:
    """A number as it is, anything else a double-quoted string (``yes``, ``null`` and ``1e3`` stay strings)."""
    return str(value) if isinstance(value, int) else yaml_string(str(value))


def _parameters(model: SystemModel) -> str:
    cpus = {core.name: i for i, core in enumerate(model.cores)}
    prio = os_priorities(model)
    roles = chain_roles(model)
    lines = [f"# The configuration of system {comment(model.name)}: rosparam loads it (launch/*.launch); the nodes",
             "# read it at start. Times are exact, in ns (\"N\" or \"N/D\"). Every string is quoted.",
             f"{yaml_string(ros_name(model.name))}:",
             "  nodes: [" + ", ".join(yaml_string(ros_name(i.name)) for i in model.instances) + "]"
             "  # they start together"]
    for inst in model.instances:
        comp = model.component(inst.component)
        lines.append(f"  {yaml_string(ros_name(inst.name))}:")
        topics, sources = [], []
        for p in comp.in_ports:
            link = model.link_into(f"{inst.name}.{p.name}")
            if link is not None:
                src_inst, src_port = link.source.split(".", 1)
                node = f"/{ros_name(model.name)}/{ros_name(src_inst)}"
                topics.append(f"      {yaml_string(p.name)}: {yaml_string(f'{node}/{src_port}')}")
                sources.append(f"      {yaml_string(p.name)}: {yaml_string(node)}")
        if topics:
            lines += ["    topics:  # the topic each connected in-port subscribes to", *topics,
                      "    sources:  # the node of the model that writes it (its messages carry records)", *sources]
        readers = {p.name: len({lk.target.split(".")[0] for lk in model.links_from(f"{inst.name}.{p.name}")})
                   for p in comp.out_ports}
        if any(readers.values()):
            lines += ["    subscribers:  # the nodes each out-port is connected to (the node starts once all are)",
                      *(f"      {yaml_string(port)}: {n}" for port, n in readers.items() if n)]
        lines.append("    tasks:")
        for task_id in inst.tasks:
            task = model.task(task_id)
            lines.append(f"      {yaml_string(task.name)}:")
            body = _activation(task) + [f"priority: {task.priority}", f"os_priority: {prio[task.priority]}",
                                        f"cpu: {cpus[task.core]}  # core {comment(task.core)}"]
            lines += [f"        {line}" for line in body]
            if task_id in roles:
                lines.append("        chains:")
                for role in roles[task_id]:
                    fields = ", ".join(f"{k}: {_yaml_scalar(v)}" for k, v in role.items())
                    lines.append(f"          - {{{fields}}}")
    return "\n".join(lines) + "\n"
