"""The sixth-order main filter of the MAC800 family (MAC800, MAC400): its registers and the
type's default setup. The loops are those of :mod:`tuning.models` on the family's numbers
(:class:`tuning.models.MotorData` with ``family`` = :data:`FAMILY`, the contract's TuningSpec of
the family whose strategy is ``"buffer_sixth_order"``; MAC800 register overview §1.2):

* servo sample TS_O = 1/770 s, 15 current-loop samples per servo sample, 8000 counts/rev, PWM
  and ADC full scale ±1023, VF_OUT full scale T_SOLL_FULL = 1023 of peak torque;
* per phase, ``U`` [PWM counts] → ``I_IST`` [ADC counts]: ``g(1 − a)/(z^d (z − a))`` with
  ``a = exp(−R·TS_I/L)``, ``g = k_u/(R·A_count)``, ``k_u = U_bus/2/1023`` V per PWM count
  (:func:`tuning.models.coil_tf`);
* the current filter (registers 144–149): IF ``(KIFX2 z² + KIFX1 z)/(z² − KIFY1 z − KIFY0)``,
  IB ``(KIB1 z + KIB0)/z`` (:func:`tuning.models.if_tf`, :func:`tuning.models.ib_tf`);
* commutation: the phase current amplitude is ``|VF_OUT|·AMPLITUDE/1023`` ADC counts
  (AMPLITUDE, register 174: ADC counts at peak torque), so the torque per VF_OUT unit is
  ``K_vf = 1.5·p·λ·A_count·AMPLITUDE/1023`` (:attr:`tuning.models.MotorData.torque_per_vf`);
* the main filter (registers 121–143, 154, 156; ``firmware/main_filter.py`` of the family)::

      e = FF(FNC_OUT) − VB(16·V_IST),   VF_OUT = KVOUT·VF(e)/2^MODEL_POT
      FF(z) = KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵,   VB(z) = KVB4 + KVB3 z⁻¹ + … + KVB0 z⁻⁴
      VF(z) = (KVFX6 + KVFX5 z⁻¹ + … + KVFX1 z⁻⁵)/(1 − KVFY5 z⁻¹ − … − KVFY0 z⁻⁶)

  with S_ORDER = 6 (every tap in use; :func:`tuning.models.ff_tf`, :func:`tuning.models.vb_tf`,
  :func:`tuning.models.vf_tf` on the family's taps);
* the speed plant VF_OUT → V_IST [counts/sample]: the closed current loop and the rigid rotor
  ``J dω/dt = K_t·i − b·ω`` at the current-loop rate, VF_OUT held for the 15 samples of a servo
  sample, the position read at the start of each servo sample, ``V_IST = (1 − z⁻¹)·P``
  (:func:`tuning.models.speed_plant`).
"""

from __future__ import annotations

from jvl_gym.families import Family, TuningSpec, families, family

from .family import default_filters

__all__ = ["FAMILY", "FAMILY_RECORD", "CONSTANTS", "STRATEGY", "TS_I", "TS_O", "COUNTS_PER_RAD",
           "FF_KEYS", "VB_KEYS", "VFX_KEYS", "VFY_KEYS", "CURRENT_KEYS", "MAIN_KEYS",
           "default_registers"]

STRATEGY = "buffer_sixth_order"  #: the strategy key of the family with this filter


def _sixth_order_family() -> Family:
    for key in families():
        fam = family(key)
        if fam.tuning is not None and fam.tuning.strategy == STRATEGY:
            return fam
    raise ImportError(f"no registered family has the tuning strategy {STRATEGY!r}")


#: the family whose tuning strategy is :data:`STRATEGY` (found by the strategy, not its key)
FAMILY_RECORD: Family = _sixth_order_family()
#: its tuning facts (the family contract's TuningSpec)
FAMILY: TuningSpec = FAMILY_RECORD.tuning  # type: ignore[assignment]
CONSTANTS = FAMILY_RECORD.constants  #: its modes, bits and scalings
TS_I: float = FAMILY.inner_dt  #: current-loop sample time [s]
TS_O: float = FAMILY.outer_dt  #: servo sample time [s]
COUNTS_PER_RAD: float = FAMILY.counts_per_rad  #: encoder counts per radian
FF_KEYS = FAMILY.ff_keys  #: KFF5 … KFF0, taps of delay 0 … 5
VB_KEYS = FAMILY.vb_keys  #: KVB4 … KVB0, taps of delay 0 … 4
VFX_KEYS = FAMILY.vfx_keys  #: KVFX6 … KVFX1, delay 0 … 5
VFY_KEYS = FAMILY.vfy_keys  #: KVFY5 … KVFY0, delay 1 … 6
CURRENT_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")
#: the main filter's registers a design sets (with S_ORDER = 6)
MAIN_KEYS = (*FF_KEYS, *VB_KEYS, *VFX_KEYS, *VFY_KEYS, "KVOUT", "MODEL_POT", "S_ORDER")


def default_registers(motor_type: str) -> dict[str, float]:
    """The current and main filter registers of the motor type's default setup (the family's
    ``configs/setups``), those it leaves out at their ROM defaults (the family's register
    table)."""
    return default_filters(motor_type, (*CURRENT_KEYS, *MAIN_KEYS))
