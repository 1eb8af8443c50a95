"""Models made from values that already have their types: ``model_construct``, made directly.

A run builds a row, its exchanges and its prediction for every key, each from values it has
just made with the right types (validating them again cost ~0.1 ms a row). Pydantic's own
``model_construct`` is generic: it checks every field for aliases, one at a time, and took
4-7 microseconds a model, a tenth of a choice run's work per item. :func:`construct` gives the
same object (the same ``__dict__``, fields set, extra and private state, so the same JSON) by
setting them at once when the values name every field of a plain model; any other call (a
field left to its default, an alias, a model with a post-init hook) goes to ``model_construct``.

Nothing here validates: a caller passes only values of the fields' types.
"""

from __future__ import annotations

from typing import Any, TypeVar

from pydantic import BaseModel

M = TypeVar("M", bound=BaseModel)

_set = object.__setattr__
#: Each model's field names in declared order, and as a set (``None``: not one :func:`construct`
#: builds directly).
_SHAPES: dict[type, tuple[tuple[str, ...], frozenset[str]] | None] = {}


def construct(model: type[M], /, **values: Any) -> M:
    """``model.model_construct(**values)``, the same object, made directly when ``values``
    names every field of ``model`` (see the module's docstring). ``model`` is positional only:
    a row has a field named ``model``."""
    try:
        shape = _SHAPES[model]
    except KeyError:  # the model's first construction
        shape = _SHAPES[model] = _shape(model)
    if shape is None or len(values) != len(shape[0]):
        return model.model_construct(**values)
    names, name_set = shape
    if tuple(values) != names:  # the fields in another order: in the declared one, as pydantic keeps them
        if values.keys() != name_set:
            return model.model_construct(**values)
        values = {name: values[name] for name in names}
    made = model.__new__(model)
    _set(made, "__dict__", values)
    _set(made, "__pydantic_fields_set__", set(name_set))  # a copy of a set: no name hashed again
    _set(made, "__pydantic_extra__", {} if model.model_config.get("extra") == "allow" else None)
    _set(made, "__pydantic_private__", None)
    return made


def _shape(model: type[BaseModel]) -> tuple[tuple[str, ...], frozenset[str]] | None:
    """``model``'s field names (in order, and as a set), or ``None`` when building it directly
    would differ from ``model_construct`` (aliases, a post-init hook, private attributes, a root model)."""
    fields = model.__pydantic_fields__
    if model.__pydantic_post_init__ or model.__pydantic_root_model__ or model.__private_attributes__:
        return None
    if any(f.alias is not None or f.validation_alias is not None for f in fields.values()):
        return None
    return tuple(fields), frozenset(fields)
