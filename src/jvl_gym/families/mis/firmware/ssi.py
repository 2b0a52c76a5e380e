"""The SSI encoder interface of the MIS/SMC firmware (MIS manual §5.7, §8.2.22 commands 320–322,
§8.2.39 EXTENCODER2, §8.2.57 SSI_SETUP1, §8.2.59 SSI_SETUP2).

User command 320 sets the RS422 lines up for an SSI encoder; 321 reads the encoder into
EXTENCODER2 and 322 does the same with a Gray → binary conversion (as does 321 with SSI_SETUP2
bit 8). A reading is ``samples`` transfers (SSI_SETUP1 bits 5–7, at least one); each transfer
takes the prepare time plus (data bits + 1) clock periods (§5.7.3: "Time = Prepare time +
(1/Clock frequency × (Number of Data bits + 1))", 2.7 ms for 100 µs, 10 kHz and 25 bits). The
encoder latches its position when a transfer starts (§5.7.4: the clock goes low "to allow the
encoder to sample and prepare a value"); the firmware keeps the data bits of the word
(SSI_SETUP1 bits 0–4). Two consecutive samples of a reading that differ by more than the largest
sample deviation (SSI_SETUP1 bits 16–28) fail the reading, which is retried up to the read
retries (bits 29–31); a reading that still fails keeps the last good value in EXTENCODER2 and
sets ERR_BITS bit 11 (§5.7.2), or with SETUP_BITS bit 20 WARN_BITS bit 7 instead
(``docs/families/mis-sim.md``, "SSI encoder").

Timing at the simulator's 1 ms outer sample: the value arrives at the first outer sample
boundary at or after the reading's end; a sample that starts within an outer sample reads the
encoder input that sample holds. This module is plain Python, run on the commands and between
outer samples by the motor array (``mis.motors``); the compiled kernel knows nothing of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["CMD_SSI_SETUP", "CMD_SSI_READ", "CMD_SSI_READ_GRAY", "ERR_SSI", "WARN_SSI",
           "SETUP_NO_SSI_ERROR", "SETUP_KEEP_SSI", "SsiSetup", "SsiReading", "gray_to_binary"]

CMD_SSI_SETUP = 320  #: set up the RS422 for an SSI encoder (§8.2.22)
CMD_SSI_READ = 321  #: read the SSI encoder into EXTENCODER2
CMD_SSI_READ_GRAY = 322  #: read it and convert from Gray code to binary
ERR_SSI = 1 << 11  #: ERR_BITS bit 11: SSI encoder (§8.2.31, §7.2.14)
WARN_SSI = 1 << 7  #: WARN_BITS bit 7: SSI encoder (§8.2.32)
SETUP_KEEP_SSI = 1 << 13  #: SETUP_BITS bit 13: do not zero EXTENCODER2 at start-up (§8.2.68)
SETUP_NO_SSI_ERROR = 1 << 20  #: SETUP_BITS bit 20: disable the SSI encoder error (§8.2.68)
#: a time a hair under a whole outer sample still ends in it (float rounding of the periods)
_EPS = 1e-9


def gray_to_binary(word: int) -> int:
    """The binary value of the Gray-coded ``word`` (≥ 0): each bit is the exclusive or of the
    Gray bits at and above it.

    Examples
    --------
    >>> gray_to_binary(0b110), gray_to_binary(0b111)
    (4, 5)
    """
    out = word
    shift = word >> 1
    while shift:
        out ^= shift
        shift >>= 1
    return out


@dataclass(frozen=True)
class SsiSetup:
    """The SSI interface's set-up from SSI_SETUP1 and SSI_SETUP2 (§8.2.57, §8.2.59).

    Attributes
    ----------
    data_bits : int
        Data bits per transfer (SSI_SETUP1 bits 0–4; 0 is read as 1).
    samples : int
        Transfers per reading (bits 5–7; 0 is read as 1).
    clock_hz : float
        Clock frequency (bits 8–15, units of 10 kHz; 0 is read as 10 kHz).
    max_deviation : int
        Largest difference of two consecutive samples of a good reading (bits 16–28).
    retries : int
        Readings repeated after a failed one (bits 29–31).
    prepare_us : int
        Prepare time in µs (SSI_SETUP2 bits 0–7; §5.7.2 and §5.7.3 give µs, §8.2.59 says ms:
        ``docs/families/mis-sim.md``, "SSI encoder").
    gray : bool
        Convert from Gray code to binary (SSI_SETUP2 bit 8).
    """

    data_bits: int
    samples: int
    clock_hz: float
    max_deviation: int
    retries: int
    prepare_us: int
    gray: bool

    @classmethod
    def of(cls, setup1: int, setup2: int) -> SsiSetup:
        """The set-up the raw register values ``setup1`` and ``setup2`` hold."""
        setup1 &= 0xFFFFFFFF
        return cls(data_bits=max(setup1 & 0x1F, 1), samples=max((setup1 >> 5) & 0x7, 1),
                   clock_hz=10_000.0 * max((setup1 >> 8) & 0xFF, 1),
                   max_deviation=(setup1 >> 16) & 0x1FFF, retries=(setup1 >> 29) & 0x7,
                   prepare_us=setup2 & 0xFF, gray=bool(setup2 & 0x100))

    @property
    def transfer_ms(self) -> float:
        """One transfer: the prepare time plus (data bits + 1) clock periods [ms]."""
        return self.prepare_us * 1e-3 + (self.data_bits + 1) / self.clock_hz * 1e3

    def value(self, word: int, gray: bool) -> int:
        """EXTENCODER2 of the encoder's ``word``: its data bits, converted from Gray code when
        ``gray``."""
        data = int(word) & ((1 << self.data_bits) - 1)
        return gray_to_binary(data) if gray else data


@dataclass
class SsiReading:
    """One reading of the SSI encoder under way (commands 321/322).

    Attributes
    ----------
    setup : SsiSetup
        The set-up at the command.
    start : int
        The motor's outer-sample count (``S_TICK``) at the command.
    gray : bool
        Convert from Gray code (command 322 or SSI_SETUP2 bit 8).
    samples : list of int
        The samples of the attempt under way.
    taken : int
        Transfers done since the command, over all attempts.
    """

    setup: SsiSetup
    start: int
    gray: bool
    samples: list[int] = field(default_factory=list)
    taken: int = 0

    def _tick(self, at_ms: float, end: bool) -> int:
        if end:
            return self.start + math.ceil(at_ms - _EPS)
        return self.start + math.floor(at_ms + _EPS)

    def next_tick(self) -> int:
        """The outer-sample count at which the reading next needs the firmware: the start of
        its next transfer, or the end of its attempt when every sample is taken."""
        t = self.setup.transfer_ms
        if len(self.samples) < self.setup.samples:
            return self._tick(self.taken * t, end=False)
        return self._tick(self.taken * t, end=True)

    def attempts(self) -> int:
        """Attempts begun (the first and the retries)."""
        return -(-self.taken // self.setup.samples) if self.taken else 0

    def take(self, word: int) -> None:
        """Latch the encoder's ``word`` as the next sample of the attempt."""
        self.samples.append(self.setup.value(word, self.gray))
        self.taken += 1

    def attempt_good(self) -> bool:
        """True if no two consecutive samples of the attempt differ by more than the largest
        sample deviation (§5.7.2)."""
        s = self.samples
        return all(abs(b - a) <= self.setup.max_deviation for a, b in zip(s, s[1:]))

    def retry(self) -> bool:
        """Start the next attempt if a retry is left (True), else False."""
        if self.attempts() > self.setup.retries:
            return False
        self.samples = []
        return True
