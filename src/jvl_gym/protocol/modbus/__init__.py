"""Modbus RTU of the MIS/SMC motors (MIS manual §12).

:mod:`.codec` the frames, addressing, PDO remapping and RTU framing (pure functions);
:mod:`.server` a Modbus RTU slave for any device of 32-bit registers over the shared transport,
with the Modbus timeout and the MacTalk → Modbus switch; :mod:`.twin` a twin's motors as Modbus
slaves (``jvl-gym serve --modbus``).

The package's own names are the codec's, as the module ``jvl_gym.protocol.modbus`` had them
before Modbus became a folder.
"""

from .codec import *  # noqa: F403
from .codec import __all__  # noqa: F401
