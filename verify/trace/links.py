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

Intra-process messages (``rclcpp_intra_publish`` → CARET's ``dispatch_intra_process_subscription_callback``)
are linked alike by a linker of their own (``Linker(intra=True)``), by a key the reader makes of the
process, the message address and the message timestamp (``lttng_events``): an address used again by a
later publish replaces the earlier one. A trace without any intra-process receipt (ros2_tracing without
CARET records the publishes only) links none of them, and that is no partial trace.
"""
from __future__ import annotations

from collections import Counter, deque
from collections.abc import Hashable

from .recording import Link, Recording

#: how many publishes of one topic wait for their receipts; an older one is given up (specs/trace.md §1.1)
WINDOW = 4096


class Linker:
    def __init__(self, intra: bool = False) -> None:
        self.intra = intra
        self.receipts = 0  # intra-process linker: the receipts seen
        # topic -> source timestamp (intra-process: a key of its own) -> (publishing node, publish time,
        # received yet)
        self.pending: dict[str, dict[Hashable, tuple[str, int, bool]]] = {}
        # topic -> (source timestamp, publish time) of the publishes waiting, oldest first
        self.order: dict[str, deque[tuple[Hashable, int]]] = {}
        self.last_taken: dict[tuple[int, int], int] = {}  # (process, subscription) -> source timestamp
        self.links: dict[tuple[str, str, str], Link] = {}
        self.unreceived: Counter[str] = Counter()  # topic -> publishes not received though later ones were
        self.given_up: dict[str, tuple[int, int]] = {}  # topic -> (how many publishes given up unreceived, when
        # the last of them was published): lost once a later one is received
        self.unpublished: Counter[str] = Counter()  # topic -> receipts without their publish
        self.last_receipt: dict[str, int] = {}  # topic -> when its last linked message was received

    def published(self, topic: str, node: str, stamp: Hashable, at: int) -> None:
        waiting = self.pending.get(topic)
        if waiting is None:
            waiting = self.pending[topic] = {}
            self.order[topic] = deque()
        order = self.order[topic]
        replaced = waiting.get(stamp)
        if replaced is not None:  # (an intra-process message address used again)
            self._give_up(topic, replaced)
        waiting[stamp] = (node, at, False)
        order.append((stamp, at))
        if len(order) > WINDOW:
            oldest, when = order.popleft()
            entry = waiting.get(oldest)
            if entry is not None and entry[1] == when:
                del waiting[oldest]
                self._give_up(topic, entry)

    def _give_up(self, topic: str, entry: tuple[str, int, bool]) -> None:
        """A publish no longer waiting: lost if it was not received and a later message is (as in ``finish``)."""
        if not entry[2]:
            count, when = self.given_up.get(topic, (0, 0))
            self.given_up[topic] = (count + 1, max(when, entry[1]))

    def received(self, topic: str, node: str, subscription: tuple[int, int], stamp: int, at: int) -> None:
        if self.last_taken.get(subscription) == stamp:
            return  # (the same message again: rmw_take, then its dispatch)
        self.last_taken[subscription] = stamp
        if not self._link(topic, node, stamp, at):
            self.unpublished[topic] += 1

    def received_intra(self, topic: str, node: str, key: Hashable, at: int) -> None:
        """A receipt of the intra-process linker (one event a message: none to tell apart)."""
        self.receipts += 1
        if not self._link(topic, node, key, at):
            self.unpublished[topic] += 1

    def _link(self, topic: str, node: str, stamp: Hashable, at: int) -> bool:
        """Link a receipt to the publish of ``topic`` with ``stamp`` (False: no such publish waits)."""
        waiting = self.pending.get(topic)
        entry = waiting.get(stamp) if waiting is not None else None
        if waiting is None or entry is None:
            return False
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
        return True

    def finish(self, out: Recording, subscribed: set[str]) -> None:
        """Hand the links to ``out``, and label it partial for the messages that could not be linked: a
        receipt without its publish (on a topic whose publishes are stamped), a publish of a topic
        subscribed in the trace that no subscription received while later ones were (those after the
        topic's last receipt were on their way when the trace ended). The intra-process linker hands
        nothing when the trace holds no intra-process receipt (its publishes cannot be linked)."""
        if self.intra and not self.receipts:
            return
        for key, link in self.links.items():
            merged = out.links.get(key)
            if merged is None:
                out.links[key] = link
            else:  # (the same nodes on one topic inter- and intra-process: one link)
                merged.delays.extend(link.delays)
        what = "intra-process message(s)" if self.intra else "message(s)"
        unreceived = Counter(self.unreceived)
        for topic, waiting in self.pending.items():
            last = self.last_receipt.get(topic, -1)
            unreceived[topic] += sum(1 for _, at, seen in waiting.values() if not seen and at < last)
        lost = sorted((t, n) for t, n in unreceived.items() if n and t in subscribed)
        if lost:
            out.partial.append(f"{what} published and not received by any subscription in the trace (lost, or "
                               "received without a trace event): " + ", ".join(f"{n} of `{t}`" for t, n in lost))
        # (a topic none of whose publishes has a source timestamp in the trace cannot be linked: ros2_tracing
        # before Jazzy without CARET, or a publisher not traced; its receipts are no sign of a trace in part)
        # (an intra-process receipt's publish is in its own process, traced alike: always a sign)
        unpublished = sorted((t, n) for t, n in self.unpublished.items() if self.intra or t in self.pending)
        if unpublished:
            out.partial.append(f"{what} received without their publish in the trace (published before it began, "
                               "or by a process not traced): " + ", ".join(f"{n} of `{t}`" for t, n in unpublished))
