"""Load test of the twin: concurrent TCP MacTalk clients, every write read back.

``python benchmarks/bench_protocol.py`` (defaults: 8 clients × 10 000 requests against one twin
with 8 MAC140 motors at addresses 1..8, one client per address). Each client mixes writes of
register-mode registers (P1..P8 LongInt, V1..V8 Integer, A1..A4 Word, L1..L4 Fixed8) — each
followed by a read that must return the written value — reads of live registers (P_IST, V_IST,
ERR_STAT) and block reads. Prints requests per second, lost (unanswered) and corrupted
(read-back mismatch) counts, and writes them to the generated page ``docs/benchmarks.md``
(section "Serial protocol", :mod:`bench_page`; ``--page`` or ``$JVL_BENCH_PAGE`` for another
file, ``none`` for no page).

The same section gets the CANopen figures (:func:`canopen_load`, ``--canopen-requests``, 0 to
skip): an MIS232 as CANopen slave (``jvl_gym.protocol.canopen``) on a python-can ``virtual``
bus with the ``canopen`` package as master — SDO round trips per second (expedited uploads and
downloads of 2012h, one after the other), received PDO frames carried out per second (RPDO 21
moving the motor) and transmitted PDO frames per second (TPDO 1 with a 1 ms event timer while
the server advances simulated time as fast as it can).
"""

from __future__ import annotations

import argparse
import random
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_page import page_path, table, update_section  # noqa: E402

from jvl_gym.protocol import MacTalkClient, NoAnswerError  # noqa: E402
from jvl_gym.protocol.mactalk.twin16 import Twin  # noqa: E402
from jvl_gym.protocol.serving.transport import TwinServer  # noqa: E402

_WRITABLE = ([(f"P{k}", -67_000_000, 67_000_000) for k in range(1, 9)]
             + [(f"V{k}", -32767, 32767) for k in range(1, 9)]
             + [(f"A{k}", 0, 65535) for k in range(1, 5)]
             + [(f"L{k}", -32767, 32767) for k in range(1, 5)])  # raw ranges


@dataclass
class LoadResult:
    """Outcome of one client (or the sum of all)."""

    requests: int = 0
    writes: int = 0
    lost: int = 0
    corrupted: int = 0
    errors: list[str] = field(default_factory=list)

    def add(self, other: LoadResult) -> None:
        self.requests += other.requests
        self.writes += other.writes
        self.lost += other.lost
        self.corrupted += other.corrupted
        self.errors += other.errors[:5]


def client_load(url: str, address: int, n_requests: int, seed: int = 0,
                timeout: float = 2.0) -> LoadResult:
    """One client: ``n_requests`` mixed requests to ``address``; every write is read back."""
    rng = random.Random(seed)
    res = LoadResult()
    with MacTalkClient(url, address=address, timeout=timeout, retries=0) as c:
        while res.requests < n_requests:
            kind = rng.random()
            try:
                if kind < 0.6 and res.requests + 2 <= n_requests:
                    name, lo, hi = rng.choice(_WRITABLE)
                    raw = rng.randint(lo, hi)
                    c.write_raw(name, raw)
                    res.writes += 1
                    back = c.read_raw(name)
                    res.requests += 2
                    if back != raw:
                        res.corrupted += 1
                        res.errors.append(f"{address}: {name} wrote {raw} read {back}")
                elif kind < 0.9:
                    c.read_raw(rng.choice(("P_IST", "V_IST", "ERR_STAT", "MYADDR")))
                    res.requests += 1
                else:
                    words = c.read_block(rng.choice((1, 49, 65)))
                    res.requests += 1
                    if len(words) != 16:
                        res.corrupted += 1
            except NoAnswerError as exc:
                res.lost += 1
                res.requests += 1
                res.errors.append(str(exc)[:120])
    return res


def run_load(url: str, addresses: list[int], n_requests: int) -> tuple[LoadResult, float]:
    """Run one client thread per address; return the summed result and the wall time."""
    results = [LoadResult() for _ in addresses]

    def work(k: int) -> None:
        results[k] = client_load(url, addresses[k], n_requests, seed=k)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(addresses))]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.perf_counter() - t0
    total = LoadResult()
    for r in results:
        total.add(r)
    return total, wall


def canopen_load(requests: int) -> dict[str, float]:
    """CANopen figures through the twin (module docstring): SDO round trips/s, RPDO and TPDO
    frames/s."""
    import can
    import canopen

    from jvl_gym import MotorArray
    from jvl_gym.protocol.canopen.eds import shipped_path
    from jvl_gym.protocol.canopen.server import CanopenServer, open_bus

    m = MotorArray("MIS232", n=1, seed=0)
    m.step(1)
    channel = f"bench-canopen-{time.monotonic_ns()}"
    server = CanopenServer([Twin(m)], open_bus("virtual", channel), run_clock=False)
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel)
    raw = can.Bus(interface="virtual", channel=channel)
    tpdos = []
    net.subscribe(0x185, lambda *_: tpdos.append(1))
    try:
        server.start()
        node = net.add_node(5, str(shipped_path()))
        t0 = time.perf_counter()
        for k in range(requests):
            if k % 2:
                node.sdo.download(0x2012, 5, (1000 + k % 1000).to_bytes(4, "little"))
            else:
                node.sdo.upload(0x2012, 10)
        sdo_rate = requests / (time.perf_counter() - t0)
        node.sdo[0x1414][1].raw = 0x215
        node.sdo[0x1A00][0].raw = 0
        node.sdo[0x1A00][1].raw = 0x20120A20
        node.sdo[0x1A00][0].raw = 1
        node.sdo[0x1800][2].raw = 255
        node.sdo[0x1800][5].raw = 1
        node.sdo[0x1800][1].raw = 0x185
        node.sdo[0x2012][2].raw = 2
        node.nmt.state = "OPERATIONAL"
        slave = server.slaves[0]
        t0 = time.perf_counter()
        for k in range(requests):
            p = (k % 100) * 100
            raw.send(can.Message(arbitration_id=0x215, is_extended_id=False,
                                 data=p.to_bytes(4, "little", signed=True)
                                 + (10000).to_bytes(2, "little") + (1000).to_bytes(2, "little")))
        while slave.stats["RPDO"] < requests and time.perf_counter() - t0 < 60:
            time.sleep(0.001)
        rpdo_rate = slave.stats["RPDO"] / (time.perf_counter() - t0)
        seconds = max(1.0, requests / 1000)
        t0 = time.perf_counter()
        server.advance(seconds)
        tpdo_rate = slave.stats["TPDO"] / (time.perf_counter() - t0)
    finally:
        server.stop()
        net.disconnect()
        raw.shutdown()
    return {"SDO round trips/s": sdo_rate, "RPDO frames/s": rpdo_rate,
            "TPDO frames/s": tpdo_rate}


def section(clients: int, requests: int, motor: str, total: LoadResult, wall: float,
            canopen: dict[str, float] | None = None) -> str:
    """The page section (Markdown) of one run (with the CANopen figures, if measured)."""
    head = (f"{clients} TCP clients × {requests:,} mixed requests against one twin "
            f"({motor} × {clients}, real-time clock running).\n\n")
    rows = [["requests/s", f"{total.requests / wall:,.0f}"],
            ["requests", f"{total.requests:,}"],
            ["writes read back", f"{total.writes:,}"],
            ["lost (unanswered)", total.lost],
            ["corrupted (read-back mismatch)", total.corrupted],
            ["wall time", f"{wall:.2f} s"]]
    text = head + table(["figure", "value"], rows)
    if canopen:
        text += ("\n\nCANopen: one MIS232 as slave on a python-can virtual bus, the canopen "
                 "package as master.\n\n"
                 + table(["figure", "value"], [[k, f"{v:,.0f}"] for k, v in canopen.items()]))
    return text


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--requests", type=int, default=10_000, help="requests per client")
    ap.add_argument("--motor", default="MAC140")
    ap.add_argument("--canopen-requests", type=int, default=2000,
                    help="SDO requests and RPDO frames of the CANopen figures (0: skip)")
    ap.add_argument("--page", default=None,
                    help="page to write (default docs/benchmarks.md; 'none': no page)")
    args = ap.parse_args(argv)
    from jvl_gym import MotorArray

    addresses = list(range(1, args.clients + 1))
    motors = MotorArray(args.motor, n=len(addresses), seed=0)
    motors.step(1)  # compile (or load) the kernel first: a first compile would outlast timeouts
    twin = Twin(motors, addresses)
    with TwinServer(twin, tcp=("127.0.0.1", 0)) as server:
        url = server.endpoint("mactalk", "tcp").url
        total, wall = run_load(url, addresses, args.requests)
    rate = total.requests / wall
    print(f"protocol load: {args.clients} TCP clients x {args.requests} mixed requests "
          f"against one twin ({args.motor} x {len(addresses)}, real-time clock running)")
    print(f"  requests {total.requests}, writes read back {total.writes}, lost {total.lost}, "
          f"corrupted {total.corrupted}")
    print(f"  wall time {wall:.2f} s, {rate:.0f} requests/s")
    for e in total.errors[:5]:
        print("  ", e)
    figures = canopen_load(args.canopen_requests) if args.canopen_requests > 0 else None
    for k, v in (figures or {}).items():
        print(f"  CANopen {k}: {v:.0f}")
    page = (page_path() if args.page is None
            else None if args.page.lower() == "none" else Path(args.page))
    if page is not None:
        update_section("protocol", section(args.clients, args.requests, args.motor, total, wall,
                                           figures), page)
        print(f"  written to {page}")
    return 0 if total.lost == 0 and total.corrupted == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
