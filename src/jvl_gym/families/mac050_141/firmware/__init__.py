"""The MAC50–141 firmware: compiled scalar kernels for one motor, composed by ``mac050_141.kernel``.

Modules: ``fixed`` (register arithmetic), ``noise`` (per-motor counter-based noise streams),
``blocks`` (function blocks, manual 4.1), ``speed_loop`` (manual 4.2 with the function
correction of docs/model.md §8), ``current_loop`` (manual 4.3), ``modes`` (mode tables, entry
actions and the rules of 4.4), ``monitor`` (manual 4.5), ``recorder`` (sample buffer, 3.2.112–116).
"""
