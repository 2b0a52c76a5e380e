"""The multifunction port of the MIS motor array as an output (MIS manual §5.5, §8.2.68,
§8.2.115, §8.2.116).

XFIELD_ADDR and XFIELD_DATA route a source to the port's RS422 lines (§5.5.1):

- XFIELD_DATA 5140 with XFIELD_ADDR 4160: the internal encoder's A and B (H2/H4 options only),
  quadrature at 1024 pulses, 4096 counts, per revolution (§5.5.2);
- XFIELD_DATA 4626 with XFIELD_ADDR 4160: the internal pulse generator (409 600 counts per
  revolution) scaled by 16, 25 600 counts per revolution, in the format SETUP_BITS bits 2–3
  select: bit 3 alone quadrature, bit 2 alone pulse/direction, neither none (§5.5.3, §5.5.4;
  the bits as §5.5's table gives them, ``docs/families/mis-sim.md``, "Multifunction port
  format bits").

Any other pair (the default 0, 0 too) routes nothing to the output: the values stay stored and
read back. The output is a world output per motor: the signed counts it emits in the last
outer sample (:attr:`MultifunctionOutput.multifunction_output`; a quadrature count is one edge
of A or B, a pulse/direction count one pulse, its sign the direction line) and their sum since
power-on. Counts are whole: each source's position is kept as the whole counts below it
(``floor``), and a sample emits the difference of two of them, so fractions carry exactly and
the sum is never more than one count from the source's own travel, however long the run.

The generator's source is the commanded microstep position the drive sends to the motor (its
direction follows SETUP_BITS bit 0 with the motor's); the encoder's is the rotor's angle, so it
counts in passive mode too when the shaft is turned. The output is settled in Python after the
compiled stepping (once before the last outer sample of a :meth:`step`, once after it, and
before every outer sample a program runs in), so the compiled kernel is untouched. A task that
advances the motors with its own compiled driver settles at the next :meth:`step`: its counts
go into the sum, not into a sample's counts.
"""

from __future__ import annotations

import math

import numpy as np

from ...motor.arguments import outer_count
from . import layout as L
from .firmware import regs as R

__all__ = ["MultifunctionOutput", "ROUTES", "XFIELD_ADDR_PORT", "XFIELD_ENCODER",
           "XFIELD_GENERATOR", "ENCODER_OUTPUT_CPR", "GENERATOR_SCALE"]

XFIELD_ADDR_PORT = 4160  #: XFIELD_ADDR of the port's output set-up (§5.5.2–5.5.4)
XFIELD_ENCODER = 5140  #: XFIELD_DATA: the internal encoder's A/B to the port (§5.5.2)
XFIELD_GENERATOR = 4626  #: XFIELD_DATA: the internal pulse generator to the port (§5.5.3)
ENCODER_OUTPUT_CPR = 4096  #: quadrature counts per revolution of the encoder output (§5.5.2)
GENERATOR_SCALE = 16  #: the pulse generator's counts per output count (§5.5.3)
#: SETUP_BITS bits 2–3, the generator output's format (§5.5.3–5.5.4 table)
SETUP_FORMAT_MASK = 0b1100
SETUP_PULSE_DIRECTION = 1 << 2
SETUP_QUADRATURE = 1 << 3
#: ENCODER_TYPE codes with the internal H2/H4 encoder (§5.5.2 "H2 or H4 option only", §8.2.49)
ENCODERS_WITH_OUTPUT = (1, 3, 4)
#: routing codes → names (:attr:`MultifunctionOutput.multifunction_routing`)
NONE, ENCODER, GENERATOR_QUADRATURE, GENERATOR_PULSE_DIRECTION, UNKNOWN = range(5)
ROUTES: dict[int, str] = {NONE: "none", ENCODER: "encoder quadrature",
                          GENERATOR_QUADRATURE: "generator quadrature",
                          GENERATOR_PULSE_DIRECTION: "generator pulse/direction",
                          UNKNOWN: "unknown"}
_ENCODER_PER_RAD = ENCODER_OUTPUT_CPR / (2.0 * math.pi)
#: the state columns of the sources: the rotor angle (encoder), the commanded position
_SOURCES = [L.S_THETA, L.S_CMD]
#: the registers the routing is read from
_ROUTING_REGISTERS = [R.XFIELD_ADDR, R.XFIELD_DATA, R.SETUP_BITS]


class MultifunctionOutput:
    """The multifunction port's output of :class:`~.motors.MisMotorArray` (a mixin over its
    arrays; module docstring)."""

    n: int
    regs: np.ndarray
    state: np.ndarray
    params: np.ndarray
    #: the registers the routing was last computed from and the routing (:meth:`_mf_routes`;
    #: None: to be computed)
    _mf_route_cache: tuple[np.ndarray, np.ndarray] | None = None
    #: the floors of ``_mf_at`` (None: to be computed); the last sample's counts (None: the
    #: output's arrays are not created yet, :meth:`_mf_arrays`)
    _mf_base: np.ndarray | None = None
    _mf_counts: np.ndarray | None = None

    # ------------------------------------------------------------------ the routing
    def _mf_routes(self) -> np.ndarray:
        """The routing code of each motor from its registers now, (N,) int (kept while
        XFIELD_ADDR, XFIELD_DATA and SETUP_BITS stay as they are; a power-on clears it)."""
        key = self.regs[:, _ROUTING_REGISTERS]
        cached = self._mf_route_cache
        if cached is not None and np.array_equal(cached[0], key):
            return cached[1]
        route = self._mf_route_of()
        self._mf_route_cache = (key, route)
        return route

    def _mf_route_of(self) -> np.ndarray:
        """:meth:`_mf_routes` computed from the registers and the encoder options."""
        regs = self.regs
        port = regs[:, R.XFIELD_ADDR] == XFIELD_ADDR_PORT
        data = regs[:, R.XFIELD_DATA]
        fmt = regs[:, R.SETUP_BITS] & SETUP_FORMAT_MASK
        code = self.params[:, L.P_ENCODER]
        has_encoder = np.zeros(self.n, bool)
        for k in ENCODERS_WITH_OUTPUT:  # (np.isin costs more on a few motors)
            has_encoder |= code == k
        out = np.where((regs[:, R.XFIELD_ADDR] != 0) | (data != 0), UNKNOWN, NONE)
        out[port & (data == XFIELD_ENCODER)] = NONE
        out[port & (data == XFIELD_GENERATOR)] = NONE
        out[port & (data == XFIELD_ENCODER) & has_encoder] = ENCODER
        gen = port & (data == XFIELD_GENERATOR)
        out[gen & (fmt == SETUP_QUADRATURE)] = GENERATOR_QUADRATURE
        out[gen & (fmt == SETUP_PULSE_DIRECTION)] = GENERATOR_PULSE_DIRECTION
        return out

    @property
    def multifunction_routing(self) -> list[str]:
        """What each motor's registers route to the multifunction port's output now:
        ``"none"`` (XFIELD_ADDR and XFIELD_DATA both 0; also the generator with SETUP_BITS
        bits 2–3 both 0 or both 1, and the encoder without an H2/H4 option),
        ``"encoder quadrature"``, ``"generator quadrature"``, ``"generator pulse/direction"``
        or ``"unknown"`` (a pair of XFIELD values §5.5 does not give: kept, nothing output)."""
        return [ROUTES[int(code)] for code in self._mf_routes()]

    # ------------------------------------------------------------------ the sources
    @staticmethod
    def _mf_floors(at: np.ndarray) -> np.ndarray:
        """The whole output counts below the sources' positions ``at`` (N, 2) (rotor angle,
        commanded position): the encoder's and the generator's, (N, 2) int64."""
        out = np.empty(at.shape, np.int64)
        out[:, 0] = np.floor(at[:, 0] * _ENCODER_PER_RAD)
        # (the commanded position is whole steps plus a carried fraction in floating point;
        # rounded to a millionth of a count, a whole step summed up as 0.999… counts is whole)
        out[:, 1] = np.floor(np.round(at[:, 1], 6) / GENERATOR_SCALE)
        return out

    def _mf_arrays(self) -> None:
        """Create the output's arrays (once; a power-on rebases them): the sources' positions
        at the last settling (and their whole counts), the last sample's counts, the sum, and
        whether the last settling found nothing routed (then a settling with no XFIELD_DATA
        set only moves the positions on)."""
        if self._mf_counts is None:
            self._mf_at = self.state[:, _SOURCES]
            self._mf_base = None
            self._mf_counts = np.zeros(self.n, np.int64)
            self._mf_total = np.zeros(self.n, np.int64)
            self._mf_quiet = False

    def _mf_power_on(self, idx: np.ndarray, state: np.ndarray | None = None) -> None:
        """Power-on or reset of motors ``idx`` (``state``: their rows of ``state`` when the
        caller holds them, (M, N_STATE)): the sources taken from here, no counts, the sum 0
        (the jump of the commanded position a reset makes emits nothing). (Attributes are
        bound only where they change: binding one costs the motor array's ``__setattr__``.)"""
        if self._mf_counts is None:
            self._mf_arrays()
        if self._mf_route_cache is not None:
            self._mf_route_cache = None
        if self._mf_base is not None:
            self._mf_base = None
        rows = self.state[idx] if state is None else state
        at = self._mf_at
        at[idx, 0] = rows[:, _SOURCES[0]]
        at[idx, 1] = rows[:, _SOURCES[1]]
        self._mf_counts[idx] = 0  # type: ignore[index]
        self._mf_total[idx] = 0

    def _mf_settle(self) -> None:
        """The counts emitted since the last settling, by the routing now; they become the
        last sample's counts and go into the sum."""
        self._mf_arrays()
        now = self.state[:, _SOURCES]
        self._mf_tick = self.state[:, L.S_TICK].copy()
        if self._mf_quiet and not self.regs[:, R.XFIELD_DATA].any():
            self._mf_at, self._mf_base = now, None
            return
        route = self._mf_routes()
        floors = self._mf_floors(now)
        base = self._mf_floors(self._mf_at) if self._mf_base is None else self._mf_base
        moved = floors - base
        counts = np.where(route == ENCODER, moved[:, 0],
                          np.where((route == GENERATOR_QUADRATURE)
                                   | (route == GENERATOR_PULSE_DIRECTION), moved[:, 1], 0))
        self._mf_at, self._mf_base = now, floors
        self._mf_counts = counts
        self._mf_total += counts
        self._mf_quiet = not ((route != NONE) & (route != UNKNOWN)).any()

    # ------------------------------------------------------------------ the world output
    @property
    def multifunction_output(self) -> np.ndarray:
        """Signed counts the multifunction port emitted in the last outer sample, (N,) int64:
        quadrature edges of A and B (4 per pulse) or, in pulse/direction format, pulses (the
        sign: the direction line); 0 where nothing is routed (:attr:`multifunction_routing`).
        """
        self._mf_arrays()
        return self._mf_counts.copy()

    @property
    def multifunction_output_total(self) -> np.ndarray:
        """Signed counts the multifunction port emitted since power-on or the last reset, the
        count a receiver of the signals holds, (N,) int64."""
        self._mf_arrays()
        return self._mf_total.copy()

    # ------------------------------------------------------------------ stepping
    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples and settle the multifunction port's
        output (module docstring)."""
        left = outer_count(n_outer, "step")
        if left == 0:
            return
        if not np.array_equal(self.state[:, L.S_TICK], getattr(self, "_mf_tick", None)):
            self._mf_settle()  # samples ran since the last settling (a compiled task's)
        if left > 1:
            super().step(left - 1)  # type: ignore[misc]
            self._mf_settle()
        super().step(1)  # type: ignore[misc]
        self._mf_settle()

    def _between_samples(self) -> None:
        """Before each outer sample a program runs in (:mod:`.program.api`): the last
        sample's counts, by the routing it ran with (the program's lines may change it)."""
        self._mf_settle()
        super()._between_samples()  # type: ignore[misc]
