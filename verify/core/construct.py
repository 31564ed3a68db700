"""Fast constructors for the frozen dataclasses built by the hundred thousand.

A frozen dataclass's ``__init__`` sets each field with a Python-level ``object.__setattr__`` call (the
class's own ``__setattr__`` refuses). A 10,000-task file has about 400,000 spans, 150,000 names and
as many other nodes, model and analysis objects; building each instance ``__dict__`` in one step
instead saves a large part of their cost. The instances are the same: same class, same ``__dict__``
(same keys in the same order), so equality, hashing, ``repr``, pickling and ``dataclasses.fields``
see no difference.

``direct_constructor(cls)`` returns such a constructor — same parameters, same defaults — for a
*plain* frozen dataclass (fields all in ``__init__``, plain defaults, no ``__post_init__``, an instance
``__dict__``), and ``cls`` itself for any other class, so a class that stops being plain only loses
the speed.
"""
from __future__ import annotations

import dataclasses
import inspect
from typing import TYPE_CHECKING, TypeGuard, TypeVar
from collections.abc import Callable

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

T = TypeVar("T")
_RESERVED = frozenset({"obj", "_new", "_set", "_cls"})  # the names the generated function uses itself


def is_plain_frozen(cls: type) -> TypeGuard[type[DataclassInstance]]:
    """``cls`` is a frozen dataclass whose instances are fully described by their ``__dict__``."""
    if not (dataclasses.is_dataclass(cls) and getattr(cls, "__dataclass_params__").frozen):  # noqa: B009 (not in the type)
        return False
    if "__post_init__" in dir(cls) or any("__slots__" in vars(k) for k in cls.__mro__[:-1]):
        return False
    # every field a parameter of ``__init__``, in order, none keyword-only (no ``InitVar``, no
    # ``init=False``, no ``kw_only``), and no default factory
    fields = dataclasses.fields(cls)
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    return ([p.name for p in params] == [f.name for f in fields]
            and all(p.kind is p.POSITIONAL_OR_KEYWORD for p in params)
            and all(f.default_factory is dataclasses.MISSING for f in fields))


def direct_constructor(cls: type[T]) -> Callable[..., T]:
    """A function building ``cls(*args, **kwargs)`` with its ``__dict__`` in one step (see above)."""
    names = [f.name for f in dataclasses.fields(cls)] if dataclasses.is_dataclass(cls) else []
    if not is_plain_frozen(cls) or any(name in _RESERVED or name.startswith("_default_") for name in names):
        return cls
    params, defaults = [], {}
    for n, f in enumerate(dataclasses.fields(cls)):
        if f.default is dataclasses.MISSING:
            params.append(f.name)
        else:
            params.append(f"{f.name}=_default_{n}")
            defaults[f"_default_{n}"] = f.default
    entries = ", ".join(f"{name!r}: {name}" for name in names)
    source = (f"def new_{cls.__name__}({', '.join(params)}):\n"
              f"    obj = _new(_cls)\n"
              f"    _set(obj, '__dict__', {{{entries}}})\n"
              f"    return obj\n")
    namespace = {"_new": object.__new__, "_set": object.__setattr__, "_cls": cls, **defaults}
    exec(source, namespace)  # as dataclasses builds __init__: one function with the fields as parameters
    make: Callable[..., T] = namespace[f"new_{cls.__name__}"]
    make.__doc__ = f"``{cls.__qualname__}(...)``, built directly (verify.core.construct)."
    return make
