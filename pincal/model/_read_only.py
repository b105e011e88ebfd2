"""Read-only objects: attributes are set while an object is made, refused afterwards.

:class:`ReadOnly` is the base of :class:`~pincal.model.Mechanism`. Its constructor sets
the attributes, then calls :meth:`ReadOnly.freeze`; from then on assigning or deleting
any attribute raises :class:`~pincal.errors.ImmutableError`, whose message says how to
get the object wanted instead (:attr:`ReadOnly.DERIVE_HINT`). A derivation (a new object
sharing most parts of this one) starts from :func:`derivation`, sets what differs, and
freezes the result.

Values computed later from a frozen object (the explored actuator ranges, the URDF text
of a derived mechanism) are kept by :meth:`ReadOnly.memo`: one cache per instance, the
one place a frozen object keeps anything after it is made; a derivation starts with an
empty cache.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar, TypeVar, cast

from pincal.errors import ImmutableError

__all__ = ["ReadOnly", "derivation"]

_T = TypeVar("_T")
_R = TypeVar("_R", bound="ReadOnly")

#: keys of the instance dict that belong to this machinery, never to the object's state
_FROZEN, _MEMO = "_read_only_frozen", "_read_only_memo"


class ReadOnly:
    """Base of objects that are not modified after they are made (see the module doc)."""

    #: what to do instead of assigning, for the error message (subclasses say theirs)
    DERIVE_HINT: ClassVar[str] = "make a new object instead"

    def __setattr__(self, name: str, value: Any) -> None:
        if self.__dict__.get(_FROZEN, False):
            raise self._refusal("set", name)
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        if self.__dict__.get(_FROZEN, False):
            raise self._refusal("delete", name)
        object.__delattr__(self, name)

    def _refusal(self, verb: str, name: str) -> ImmutableError:
        kind = type(self).__name__
        return ImmutableError(
            f"cannot {verb} attribute {name!r}: a {kind} is read-only once made "
            f"(its parts are shared with the {kind}s derived from it); {self.DERIVE_HINT}"
        )

    def freeze(self) -> None:
        """Refuse every later assignment or deletion of an attribute.

        The last step of a constructor or of a derivation; calling it again does nothing.
        """
        self.__dict__[_FROZEN] = True

    def memo(self, key: str, build: Callable[[], _T]) -> _T:
        """The value kept under ``key``, computed by ``build()`` on first use.

        For values derived from this (read-only) object by other modules, e.g.
        ``memo("explored_ranges", lambda: explore(mech))``; ``key`` names the value,
        one key per kind of value.
        """
        cache: dict[str, object] = self.__dict__.setdefault(_MEMO, {})
        if key not in cache:
            cache[key] = build()
        return cast(_T, cache[key])


def derivation(obj: _R) -> _R:
    """A new object of ``obj``'s class sharing its attributes, not frozen, with no memo.

    For the module that defines the class: set the attributes that differ, then call
    :meth:`ReadOnly.freeze` on the result before handing it out.
    """
    new = object.__new__(type(obj))
    state = {k: v for k, v in obj.__dict__.items() if k not in (_FROZEN, _MEMO)}
    new.__dict__.update(state)
    return new
