"""The watchdog process of a deployed policy (:class:`jvl_gym.rl.supervisor.Watchdog`).

``python -m jvl_gym.rl.watchdog URL ADDRESS MOTOR_TYPE TIMEOUT`` connects to the motor on its
own, prints ``ready`` and reads its standard input: ``.`` is a heartbeat, ``!`` puts the motor
passive now, ``q`` ends it quietly. When no byte comes for ``TIMEOUT`` seconds, or the input
closes (the loop's process ended, even by SIGKILL), it puts the motor passive (MODE_REG = the
family's ``twin.passive_mode``) and ends, printing what it did.
"""

from __future__ import annotations

import os
import select
import sys
import time
from typing import Any

__all__ = ["main", "passive_client"]


def passive_client(url: str, address: int, motor_type: str, timeout: float = 0.2) -> Any:
    """A MacTalk client of the motor's dialect (``family_of_motor``) with a ``passive()`` that
    writes the family's passive mode."""
    from ..families import family_of_motor
    from ..protocol.mactalk import codec16
    from ..protocol.mactalk.client16 import MacTalkClient
    from ..protocol.mactalk.client32 import MacTalk32Client

    fam = family_of_motor(motor_type)
    cls = MacTalkClient if fam.twin.dialect == codec16.DIALECT else MacTalk32Client
    client = cls(url, address, timeout=timeout, retries=1, table=fam.table)
    mode = fam.twin.passive_mode
    if mode is None:
        raise ValueError(f"family {fam.key} has no passive mode")

    def passive() -> None:
        client.write("MODE_REG", int(mode))

    # the write's checks run once now: the first call loads compiled code, which can take
    # seconds in a fresh process, and must not delay the stop
    from ..registers import to_raw, to_word16

    reg = fam.table.lookup("MODE_REG")
    to_word16(reg, int(to_raw(reg, int(mode))))
    client.read("MODE_REG")  # the connection answers
    client.passive = passive
    return client


#: attempts of the passive write before the watchdog gives up (each the client's time-out
#: and retry: a few seconds in all, for a motor that answers late on a loaded line)
PASSIVE_ATTEMPTS = 10


def _passive(client: Any, why: str) -> None:
    for _ in range(PASSIVE_ATTEMPTS):
        try:
            client.passive()
            print(f"passive: {why}", flush=True)
            return
        except Exception as exc:  # noqa: BLE001 - report and try again
            error = exc
    print(f"failed: {why}: {error}", flush=True)


def main(argv: list[str] | None = None) -> int:
    """Run the watchdog (module docstring); exit status 0."""
    url, address, motor_type, timeout = (argv if argv is not None else sys.argv[1:])[:4]
    seconds = float(timeout)
    client = passive_client(url, int(address), motor_type)
    fd = sys.stdin.fileno()
    print("ready", flush=True)
    last = time.monotonic()
    while True:
        wait = max(0.0, last + seconds - time.monotonic())
        ready, _, _ = select.select([fd], [], [], wait)
        if not ready:
            _passive(client, f"no heartbeat for {seconds:g} s")
            return 0
        data = os.read(fd, 4096)
        if not data:
            _passive(client, "the loop's process ended")
            return 0
        if b"!" in data:
            _passive(client, "the loop stopped")
            return 0
        if b"q" in data:
            return 0
        last = time.monotonic()


if __name__ == "__main__":
    sys.exit(main())
