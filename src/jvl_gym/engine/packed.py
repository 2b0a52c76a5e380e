"""Many arrays passed to compiled code as one argument (:class:`PackedArguments`).

Each array argument of a compiled call is converted at the call: its type checked, its data
pointer, shape and strides read from the Python object. An env step passes its motors',
episode's and task's arrays, some twenty: with nothing to step (decimation 0) a one-copy
Positioning step's call took 0.41 µs, GearSync's 0.46 µs. These arrays stay the same objects
for the env's life, so their pointers, shapes and strides can be read once:
:class:`PackedArguments` keeps them in one int64 table and passes as one pointer, and
:func:`unpack`, inside the compiled code, rebuilds the arrays from the table, with the numba
types the arrays had when the table was made (the same calls: 0.26 and 0.30 µs). The compiled
code then runs on the same memory as the Python arrays.

The table does not own the arrays' memory: a :class:`PackedArguments` holds the arrays, and the
compiled code must not keep them past the call (the rebuilt arrays have no reference count,
as in :data:`jvl_gym.engine.jit.KERNEL` code). An array whose memory is replaced (a new array
bound in its place) needs a new table.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from llvmlite import ir
from numba import typeof
from numba.core import cgutils, types
from numba.extending import NativeValue, intrinsic, models, register_model, typeof_impl, unbox
from numba.np.arrayobj import populate_array

__all__ = ["PackedArguments", "PackedType", "unpack"]


class PackedType(types.Type):
    """The numba type of a :class:`PackedArguments`: the types of its arguments, ``members``
    (a numba tuple type, nested where an argument is a tuple)."""

    def __init__(self, members: types.BaseTuple) -> None:
        self.members = members
        super().__init__(name=f"Packed{members}")


register_model(PackedType)(models.OpaqueModel)


def _words(value: Any, kind: types.Type) -> list[int]:
    """The table words of one argument of numba type ``kind``: an array's data address, shape
    and strides; an integer or a bool as itself; a tuple's members in order."""
    if isinstance(kind, types.BaseTuple):
        return [w for v, k in zip(value, kind) for w in _words(v, k)]
    if isinstance(kind, types.Array):
        return [value.ctypes.data, *value.shape, *value.strides]
    if isinstance(kind, (types.Integer, types.Boolean)):
        return [(int(value) + 2**63) % 2**64 - 2**63]  # the 64 bits, as a signed word
    raise TypeError(f"PackedArguments takes arrays, integers, bools and tuples of them, not "
                    f"{kind}")


class PackedArguments:
    """Arguments of a compiled call, converted once (module docstring).

    Parameters
    ----------
    args : tuple
        Arrays, integers, bools and (nested) tuples of them. The arrays are kept, and the
        compiled code works on their memory; an integer or bool is its value at this call.
    """

    def __init__(self, args: tuple) -> None:
        self.args = tuple(args)
        try:
            members = typeof(self.args)
        except ValueError:  # numba has no type for one of them
            members = None
        if not isinstance(members, types.BaseTuple):
            raise TypeError("PackedArguments takes arrays, integers, bools and tuples of them, "
                            f"not {[type(a).__name__ for a in self.args]}")
        #: the numba type the compiled code sees (:class:`PackedType`)
        self.numba_type = PackedType(members)
        self._table = np.array(_words(self.args, members), dtype=np.int64)
        #: the table's address, read by the compiled call's argument conversion
        self.address = self._table.ctypes.data

    def __reduce__(self) -> tuple:
        # a copy packs its own arrays (a copied table would point at the original's)
        return (PackedArguments, (self.args,))


@typeof_impl.register(PackedArguments)
def _typeof_packed(value: PackedArguments, context: Any) -> PackedType:
    return value.numba_type


@unbox(PackedType)
def _unbox_packed(typ: PackedType, obj: Any, c: Any) -> NativeValue:
    """A :class:`PackedArguments` converted to its table's address."""
    address = c.pyapi.object_getattr_string(obj, "address")
    with cgutils.if_unlikely(c.builder, cgutils.is_null(c.builder, address)):
        c.builder.ret(c.pyapi.get_null_object())  # the AttributeError is set
    pointer = c.pyapi.long_as_voidptr(address)
    c.pyapi.decref(address)
    return NativeValue(pointer, is_error=c.pyapi.c_api_error())


@intrinsic
def unpack(typingctx: Any, packed: PackedType) -> Any:  # pragma: no cover - compiled
    """The arguments of ``packed`` (a :class:`PackedArguments`) as a tuple of the types they
    had when it was made, rebuilt from its table (compiled code only)."""
    if not isinstance(packed, PackedType):
        return None
    members = packed.members

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        word_type = ir.IntType(64)
        table = builder.bitcast(args[0], word_type.as_pointer())
        position = [0]

        def word() -> Any:
            at = builder.gep(table, [ir.Constant(word_type, position[0])])
            position[0] += 1
            return builder.load(at)

        def build(kind: types.Type) -> Any:
            if isinstance(kind, types.BaseTuple):
                return context.make_tuple(builder, kind, [build(k) for k in kind])
            if isinstance(kind, types.Array):
                struct = context.make_array(kind)(context, builder)  # numba's array struct
                data = builder.inttoptr(word(), struct.data.type)
                shape = [word() for _ in range(kind.ndim)]
                strides = [word() for _ in range(kind.ndim)]
                itemsize = context.get_abi_sizeof(context.get_data_type(kind.dtype))
                populate_array(struct, data=data,
                               shape=cgutils.pack_array(builder, shape, ty=word_type),
                               strides=cgutils.pack_array(builder, strides, ty=word_type),
                               itemsize=context.get_constant(types.intp, itemsize),
                               meminfo=None)
                return struct._getvalue()
            value = word()
            if isinstance(kind, types.Boolean):
                return builder.icmp_unsigned("!=", value, ir.Constant(word_type, 0))
            return context.cast(builder, value, types.int64, kind)

        return build(members)

    return members(packed), codegen
