"""The SDO server of a node (MIS manual §11.9.4): the ``canopen`` package's
:class:`~canopen.sdo.SdoServer` with the checks a slave on a real bus needs.

``canopen``'s server does expedited and segmented uploads and downloads; this subclass adds

* a request of other than 8 bytes, a segment without an initiated transfer, a block transfer or
  an unknown command specifier: abort 0504 0001h ("client/server command specifier not valid or
  unknown");
* a segment whose toggle bit did not alternate: abort 0503 0000h, and the transfer ends;
* a segmented download is checked (object, sub-index, write access) at its initiation, not
  only after the last segment, and the data are written once, whole, after the last one;
* a download whose data are longer or shorter than the object: 0607 0012h / 0607 0013h; a
  segmented download that passes its announced size or :data:`MAX_DOWNLOAD` bytes is aborted
  (0607 0012h) at that segment, and the transfer ends (the data held are bounded).

Every abort names the object of the request; nothing is written by a refused request. The
node (:class:`~.slave.CanopenSlave`) raises :class:`~canopen.SdoAbortedError` with the
manual's code for an object it refuses.
"""

from __future__ import annotations

import struct
from typing import Any

from canopen.sdo import SdoAbortedError, SdoServer
from canopen.sdo.constants import (
    EXPEDITED,
    NO_MORE_DATA,
    REQUEST_ABORTED,
    REQUEST_DOWNLOAD,
    REQUEST_SEGMENT_DOWNLOAD,
    REQUEST_SEGMENT_UPLOAD,
    REQUEST_UPLOAD,
    RESPONSE_DOWNLOAD,
    RESPONSE_SEGMENT_DOWNLOAD,
    SDO_STRUCT,
    SIZE_SPECIFIED,
    TOGGLE_BIT,
)

__all__ = ["NodeSdoServer", "ABORT", "MAX_DOWNLOAD"]

#: bytes a segmented download may carry at most (every writable object of the dictionary holds
#: 4 bytes at most): a longer one is aborted with 0607 0012h at the segment that passes it
MAX_DOWNLOAD = 256

#: the abort codes of MIS manual §11.9.4 this server and its node use
ABORT = {
    "toggle": 0x05030000, "command": 0x05040001, "unsupported": 0x06010000,
    "write_only": 0x06010001, "read_only": 0x06010002, "no_object": 0x06020000,
    "not_mappable": 0x06040041, "pdo_length": 0x06040042, "incompatible": 0x06040043,
    "length": 0x06070010, "too_long": 0x06070012, "too_short": 0x06070013,
    "no_sub": 0x06090011, "range": 0x06090030, "too_high": 0x06090031, "too_low": 0x06090032,
    "general": 0x08000000, "store": 0x08000020, "local": 0x08000021, "state": 0x08000022,
}


class NodeSdoServer(SdoServer):
    """SDO server of ``node`` on ``rx_cobid`` → ``tx_cobid`` (0x600/0x580 + node id).

    Parameters
    ----------
    rx_cobid, tx_cobid : int
        Request and response COB-IDs.
    node : CanopenSlave
        Has ``object_dictionary``, ``get_data(index, sub, check_readable)`` and
        ``set_data(index, sub, data, check_writable)`` and ``check_download(index, sub)``.
    """

    def __init__(self, rx_cobid: int, tx_cobid: int, node: Any) -> None:
        super().__init__(rx_cobid, tx_cobid, node)
        self._index = 0
        self._subindex = 0
        self._active: int | None = None  # REQUEST_UPLOAD / REQUEST_DOWNLOAD while segmented

    def on_request(self, can_id: int, data: bytes, timestamp: float) -> None:
        """Answer one request frame (a response or an abort)."""
        data = bytes(data)
        if len(data) != 8:
            if len(data) >= 4:
                _, self._index, self._subindex = SDO_STRUCT.unpack_from(data)
            self._active = None
            self.abort(ABORT["command"])
            return
        command = data[0]
        ccs = command & 0xE0
        try:
            if ccs == REQUEST_UPLOAD:
                self._active = None
                self._buffer = None
                self.init_upload(data)
                if self._buffer:
                    self._active = REQUEST_UPLOAD
            elif ccs == REQUEST_DOWNLOAD:
                self._active = None
                self.init_download(data)
            elif ccs == REQUEST_SEGMENT_UPLOAD and self._active == REQUEST_UPLOAD:
                self._segment_toggle(command)
                self.segmented_upload(command)
                if not self._buffer:
                    self._active = None
            elif ccs == REQUEST_SEGMENT_DOWNLOAD and self._active == REQUEST_DOWNLOAD:
                self._segment_toggle(command)
                self.segmented_download(command, data)
            elif ccs == REQUEST_ABORTED:
                self._active = None
                self.request_aborted(data)
            else:
                self._active = None
                self.abort(ABORT["command"])
        except SdoAbortedError as exc:
            self._active = None
            self.abort(exc.code)

    def _segment_toggle(self, command: int) -> None:
        if command & TOGGLE_BIT != self._toggle:
            raise SdoAbortedError(ABORT["toggle"])

    def init_download(self, request: bytes) -> None:
        command, index, subindex = SDO_STRUCT.unpack_from(request)
        self._index, self._subindex = index, subindex
        if command & EXPEDITED:
            size = 4 - ((command >> 2) & 0x3) if command & SIZE_SPECIFIED else 4
            self._node.set_data(index, subindex, request[4:4 + size], check_writable=True)
        else:
            self._node.check_download(index, subindex)
            self._size = struct.unpack_from("<L", request, 4)[0] if command & SIZE_SPECIFIED \
                else None
            self._buffer = bytearray()
            self._toggle = 0
            self._active = REQUEST_DOWNLOAD
        response = bytearray(8)
        SDO_STRUCT.pack_into(response, 0, RESPONSE_DOWNLOAD, index, subindex)
        self.send_response(response)

    def segmented_download(self, command: int, request: bytes) -> None:
        last_byte = 8 - ((command >> 1) & 0x7)
        self._buffer.extend(request[1:last_byte])
        if len(self._buffer) > (MAX_DOWNLOAD if self._size is None
                                else min(MAX_DOWNLOAD, self._size)):
            self._active = None
            self._buffer = bytearray()
            raise SdoAbortedError(ABORT["too_long"])
        if command & NO_MORE_DATA:
            self._active = None
            if self._size is not None and self._size != len(self._buffer):
                raise SdoAbortedError(ABORT["too_long"] if len(self._buffer) > self._size
                                      else ABORT["too_short"])
            self._node.set_data(self._index, self._subindex, bytes(self._buffer),
                                check_writable=True)
        response = bytearray(8)
        response[0] = RESPONSE_SEGMENT_DOWNLOAD | self._toggle
        self._toggle ^= TOGGLE_BIT
        self.send_response(response)
