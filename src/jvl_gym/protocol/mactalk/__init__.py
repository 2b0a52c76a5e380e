"""MacTalk, the motors' own serial protocol, in both dialects, with FastMAC and FlexMAC.

=================  ====================================================================
:mod:`.codec16`    MacTalk of the MAC050–141 (manual 5.1): frames, bytes in / bytes out
:mod:`.codec32`    MacTalk of the 32-bit register families (MAC800 quick guide §1.3, MIS
                   manual §18.2)
:mod:`.fastmac`    FastMAC user interface (MAC050–141 manual 5.2.1)
:mod:`.flexmac`    FlexMAC user interface (5.2.2)
:mod:`.stream`     the resynchronising stream decoder the codecs share
:mod:`.dialect`    which MacTalk a family speaks
:mod:`.master`     the serial master: port, timeout, retries
:mod:`.client16`   :class:`MacTalkClient`, typed reads and writes by register name (16-bit)
:mod:`.client32`   :class:`MacTalk32Client`, the same in the 32-bit dialect
:mod:`.probe`      which dialect a unit on a line speaks
:mod:`.twin16`     the serving side: a twin's motors answering MacTalk, FastMAC and FlexMAC
:mod:`.twin32`     the 32-bit dialect's unit of a twin
:mod:`.line`       motors of several families on one line, each in its own dialect
=================  ====================================================================

The package's own names are the 16-bit codec's (``jvl_gym.protocol.mactalk.Request`` …), as the
module ``jvl_gym.protocol.mactalk`` had them before MacTalk became a folder.
"""

from .codec16 import *  # noqa: F403
from .codec16 import __all__  # noqa: F401
