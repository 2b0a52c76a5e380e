"""The DSP-402 homing methods (object 6098h; MIS manual §11.5.6) as the motor's own zero
searches (MIS manual §6.5, ZERO_SEARCH_BITS §8.2.67).

§11.5.6 says "the standard Homing Search modes from 1-34 are supported" and its table names
−4, −3 (torque), 1, 2 (limit switch), 3–6 (home switch edge and direction), 17–22 ("same as
1–6 without index") and 35; docs/protocol.md "Homing methods" has the readings and the choice.
Every method is carried out with the motor's zero search, which finds a switch edge at the
crawl velocity and, with ZERO_SEARCH_BITS bit 0, goes on to the encoder index:

* 1–6 as the table names them (1, 2: type 2 onto the negative / positive limit switch, which
  is also the home input (§11.5.6, "Homing on limit switch"), and off it at the crawl velocity,
  as the standard's 1, 2; 3, 4: type 1, the rising edge of the home switch in the negative /
  positive direction; 5, 6: type 2, its falling edge after reversing), then on to the index;
  17–22 the same without the index.
* 7–14 (CiA 402: home switch between the limit switches, initial motion positive for 7–10,
  negative for 11–14) and 23–30 (the same without index): when the home switch is not active
  at the start, a first search in the initial direction, turning at a limit switch
  (ZERO_SEARCH_BITS bit 1), stops on the switch; then the final search from the switch finds
  the method's edge approached in the method's direction: the lower edge (the switch's
  negative end) for 7, 8, 13, 14, the upper for 9–12; approached moving negative for 7, 9,
  12, 14, positive for 8, 10, 11, 13. Leaving the switch at that edge is a type 2 search
  seeking the other way (it reverses at the crawl velocity until the switch is released);
  entering it there is a type 2 search with bit 2 (out of the switch at the search velocity,
  back onto it at the crawl velocity).
* 33, 34: the index in the negative / positive direction (bit 4 "ignore switch" with bit 0).
* −3, −4: the torque zero search (no home input) in the negative / positive direction.

15, 16, 31 and 32 are reserved by the standard (no behaviour to carry out) and −2, −1 and 35
are "No" in §11.5.6's table: 6098h refuses them.

The index is the internal encoder's, once per revolution (as the motor's own "use index after
zero search"); a motor without an encoder has no index, and its search ends at the switch edge
(33, 34: where the motor stands), as the motor's own zero search does.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["HOMING_METHODS", "Search", "Method", "METHODS"]


@dataclass(frozen=True)
class Search:
    """One zero search of the motor (MODE_REG 13 or 14, V_HOME's sign, ZERO_SEARCH_BITS).

    Attributes
    ----------
    type2 : bool
        Zero search type 2 (reverse off the switch at the crawl velocity), else type 1.
    direction : int
        +1 or −1: the sign of V_HOME, the way the search first moves.
    opposite : bool
        Bit 2: the switch's far side.
    ignore_switch : bool
        Bit 4: no switch, the zero where the motor stands (or the next index).
    torque : bool
        The torque zero search: no home input (HOME_MASK 0).
    """

    type2: bool
    direction: int
    opposite: bool = False
    ignore_switch: bool = False
    torque: bool = False


@dataclass(frozen=True)
class Method:
    """A homing method: the final search, whether the index follows it, and the initial
    direction of a first search onto the home switch (0: none).

    ``user_options``: the user's ZERO_SEARCH_BITS bits 1 and 2 apply (the table's methods
    1–6 and 17–22, which are the motor's zero search as set up, §11.5.6).
    """

    final: Search
    index: bool
    seek: int = 0
    user_options: bool = False


def _table() -> dict[int, Method]:
    t: dict[int, Method] = {
        -4: Method(Search(False, 1, torque=True), False),
        -3: Method(Search(False, -1, torque=True), False),
        33: Method(Search(False, -1, ignore_switch=True), True),
        34: Method(Search(False, 1, ignore_switch=True), True),
    }
    table_1_6 = {1: Search(True, -1), 2: Search(True, 1), 3: Search(False, -1),
                 4: Search(False, 1), 5: Search(True, -1), 6: Search(True, 1)}
    for n, search in table_1_6.items():
        t[n] = Method(search, True, user_options=True)
        t[n + 16] = Method(search, False, user_options=True)
    # 7-14: (final search: type 2 seeking ``direction``, with bit 2 when the edge is entered)
    leave_low, enter_low = Search(True, 1), Search(True, -1, opposite=True)
    enter_high, leave_high = Search(True, 1, opposite=True), Search(True, -1)
    finals = {7: leave_low, 8: enter_low, 9: enter_high, 10: leave_high,
              11: leave_high, 12: enter_high, 13: enter_low, 14: leave_low}
    for n, search in finals.items():
        seek = 1 if n <= 10 else -1
        t[n] = Method(search, True, seek=seek)
        t[n + 16] = Method(search, False, seek=seek)
    return dict(sorted(t.items()))


#: every method 6098h takes (module text)
METHODS: dict[int, Method] = _table()
#: their numbers
HOMING_METHODS: tuple[int, ...] = tuple(METHODS)
