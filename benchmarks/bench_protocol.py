"""Load test of the twin: concurrent TCP MacTalk clients, every write read back.

``python benchmarks/bench_protocol.py`` (defaults: 8 clients × 10 000 requests against one twin
with 8 MAC140 motors at addresses 1..8, one client per address). Each client mixes writes of
register-mode registers (P1..P8 LongInt, V1..V8 Integer, A1..A4 Word, L1..L4 Fixed8) — each
followed by a read that must return the written value — reads of live registers (P_IST, V_IST,
ERR_STAT) and block reads. Prints requests per second, lost (unanswered) and corrupted
(read-back mismatch) counts, and writes them to the generated page ``docs/benchmarks.md``
(section "Serial protocol", :mod:`bench_page`; ``--page`` or ``$JVL_BENCH_PAGE`` for another
file, ``none`` for no page).
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
from jvl_gym.protocol.transport import TwinServer  # noqa: E402
from jvl_gym.protocol.twin import Twin  # noqa: E402

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


def section(clients: int, requests: int, motor: str, total: LoadResult, wall: float) -> str:
    """The page section (Markdown) of one run."""
    head = (f"{clients} TCP clients × {requests:,} mixed requests against one twin "
            f"({motor} × {clients}, real-time clock running).\n\n")
    rows = [["requests/s", f"{total.requests / wall:,.0f}"],
            ["requests", f"{total.requests:,}"],
            ["writes read back", f"{total.writes:,}"],
            ["lost (unanswered)", total.lost],
            ["corrupted (read-back mismatch)", total.corrupted],
            ["wall time", f"{wall:.2f} s"]]
    return head + table(["figure", "value"], rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--requests", type=int, default=10_000, help="requests per client")
    ap.add_argument("--motor", default="MAC140")
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
    page = (page_path() if args.page is None
            else None if args.page.lower() == "none" else Path(args.page))
    if page is not None:
        update_section("protocol", section(args.clients, args.requests, args.motor, total, wall),
                       page)
        print(f"  written to {page}")
    return 0 if total.lost == 0 and total.corrupted == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
