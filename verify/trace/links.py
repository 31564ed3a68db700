"""Messages of an LTTng trace linked from their publish to their receipt (specs/trace.md §1.1), as CARET
links them: a publish (``rcl_publish``: publisher, message address, time) gets its *source timestamp*
from the event that follows it on its thread for the same message address (CARET's
``dds_bind_addr_to_stamp``, ros2_tracing's ``rmw_publish`` with its ``timestamp``); a receipt
(ros2_tracing's ``rmw_take``, CARET's ``dispatch_subscription_callback``) carries the source timestamp
of the message it took. A receipt is linked to the publish of its topic with the same source timestamp.

Streaming, with memory bounded by the model: per topic the publishes waiting for their receipts (at
most ``WINDOW``: an older one is given up), per subscription the last timestamp taken (a message that
both ``rmw_take`` and ``dispatch_subscription_callback`` report is one receipt), and per link (topic,
publishing node, subscribing node) an array of delays, 8 bytes a message.
"""
from __future__ import annotations

from collections import Counter, deque

from .recording import Link, Recording

#: how many publishes of one topic wait for their receipts; an older one is given up (specs/trace.md §1.1)
WINDOW = 4096


class Linker:
    def __init__(self) -> None:
        # topic -> source timestamp -> (publishing node, publish time, received yet), oldest first
        self.pending: dict[str, dict[int, tuple[str, int, bool]]] = {}
        self.order: dict[str, deque[int]] = {}  # topic -> the source timestamps waiting, oldest first
        self.last_taken: dict[tuple[int, int], int] = {}  # (process, subscription) -> source timestamp
        self.links: dict[tuple[str, str, str], Link] = {}
        self.unreceived: Counter[str] = Counter()  # topic -> publishes not received though later ones were
        self.given_up: dict[str, tuple[int, int]] = {}  # topic -> (how many publishes given up unreceived, when
        # the last of them was published): lost once a later one is received
        self.unpublished: Counter[str] = Counter()  # topic -> receipts without their publish
        self.last_receipt: dict[str, int] = {}  # topic -> when its last linked message was received

    def published(self, topic: str, node: str, stamp: int, at: int) -> None:
        waiting = self.pending.get(topic)
        if waiting is None:
            waiting = self.pending[topic] = {}
            self.order[topic] = deque()
        order = self.order[topic]
        waiting[stamp] = (node, at, False)
        order.append(stamp)
        if len(order) > WINDOW:
            given_up = waiting.pop(order.popleft())
            if not given_up[2]:  # (lost if a later message is received, as in ``finish``)
                count, _ = self.given_up.get(topic, (0, 0))
                self.given_up[topic] = (count + 1, given_up[1])

    def received(self, topic: str, node: str, subscription: tuple[int, int], stamp: int, at: int) -> None:
        if self.last_taken.get(subscription) == stamp:
            return  # (the same message again: rmw_take, then its dispatch)
        self.last_taken[subscription] = stamp
        waiting = self.pending.get(topic)
        entry = waiting.get(stamp) if waiting is not None else None
        if waiting is None or entry is None:
            self.unpublished[topic] += 1
            return
        publisher, published, received = entry
        if not received:
            waiting[stamp] = (publisher, published, True)
        key = (topic, publisher, node)
        link = self.links.get(key)
        if link is None:
            link = self.links[key] = Link(topic, publisher, node)
        link.delays.append(at - published)
        self.last_receipt[topic] = at
        if self.given_up:
            lost = self.given_up.get(topic)
            if lost is not None and lost[1] < published:
                self.unreceived[topic] += lost[0]
                del self.given_up[topic]

    def finish(self, out: Recording, subscribed: set[str]) -> None:
        """Hand the links to ``out``, and label it partial for the messages that could not be linked: a
        receipt without its publish (on a topic whose publishes are stamped), a publish of a topic
        subscribed in the trace that no subscription received while later ones were (those after the
        topic's last receipt were on their way when the trace ended)."""
        out.links.update(self.links)
        unreceived = Counter(self.unreceived)
        for topic, waiting in self.pending.items():
            last = self.last_receipt.get(topic, -1)
            unreceived[topic] += sum(1 for _, at, seen in waiting.values() if not seen and at < last)
        lost = sorted((t, n) for t, n in unreceived.items() if n and t in subscribed)
        if lost:
            out.partial.append("message(s) published and not received by any subscription in the trace (lost, or "
                               "received without a trace event): " + ", ".join(f"{n} of `{t}`" for t, n in lost))
        # (a topic none of whose publishes has a source timestamp in the trace cannot be linked: ros2_tracing
        # before Jazzy without CARET, or a publisher not traced; its receipts are no sign of a trace in part)
        unpublished = sorted((t, n) for t, n in self.unpublished.items() if t in self.pending)
        if unpublished:
            out.partial.append("message(s) received without their publish in the trace (published before it began, "
                               "or by a process not traced): " + ", ".join(f"{n} of `{t}`" for t, n in unpublished))
