"""The UV_HANDLE reaction to an under-voltage (compiled): which bits of the handle register
set the error bit, stop the profile and ask for the passive state.

MAC050–141 manual 3.2.160 and 4.5.6 (UV_HANDLE bit 0 SET_UV_ERR, bit 1 UV_GO_PASSIVE, bit 3
UV_SOLL0); MAC800 register overview §1.2, register 23 (bit 0 SET_UV_ERR, bit 1 UV_GO_PASSIVE,
bit 2 UV_VSOLL0). A family states its register numbers and bit masks once, as a
:class:`UvHandle` tuple, and decides itself when an under-voltage is reacted to and what going
passive means for it (the MAC050–141 stops to INIT_MODE with ACC_EMERG, the MAC800 goes to
mode 0 at once).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..engine.jit import KERNEL

__all__ = ["UvHandle", "uv_handle_reaction"]


class UvHandle(NamedTuple):
    """A family's UV_HANDLE facts: register numbers (columns of a register row) and masks; a
    module global of the family's firmware, so the compiled code reads them as constants."""

    handle: int  #: the UV_HANDLE register
    err_stat: int  #: the register holding the UV_ERR bit (ERR_STAT)
    uv_err: int  #: mask of UV_ERR in ``err_stat``
    v_soll: int  #: the V_SOLL register, set to 0 to stop the profile
    set_uv_err: int  #: mask of the handle bit that sets UV_ERR
    stop_profile: int  #: mask of the handle bit that sets V_SOLL = 0
    go_passive: int  #: mask of the handle bit that asks for the passive state


@njit(**KERNEL)
def uv_handle_reaction(r: np.ndarray, facts: UvHandle) -> bool:
    """React to an under-voltage as UV_HANDLE says; whether it asks for the passive state.

    Parameters
    ----------
    r : numpy.ndarray, shape (n_registers,)
        One motor's register row.
    facts : UvHandle
        The family's registers and bits.

    Returns
    -------
    bool
        UV_GO_PASSIVE is set: the caller takes the motor to its passive state. UV_ERR (with
        SET_UV_ERR) and V_SOLL = 0 (with the stop bit) are written here, in that order.
    """
    h = r[facts.handle]
    if h & facts.set_uv_err:
        r[facts.err_stat] |= facts.uv_err
    if h & facts.stop_profile:
        r[facts.v_soll] = 0
    return (h & facts.go_passive) != 0
