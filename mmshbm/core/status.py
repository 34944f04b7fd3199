"""Why a branch stopped: :class:`Status`, a string with a kind and a detail.

The continuation driver ends every branch with a status. Its text is what files have
always held (``"bound:amplitude"``, ``"ds_min: step size fell below 1e-07 (...)"``,
``"max_steps"``, ...), and a :class:`Status` *is* that text (a ``str`` subclass): it
compares equal to it, saves as it and prints as it. Code that acts on a status reads
``status.kind`` (``"bound"``, ``"ds_min"``, ...) and ``status.detail`` (the bound's name,
the failure's message) instead of parsing the text; :meth:`Status.parse` gives both for a
plain string (a status read back from a file).

Kinds the driver produces:

==========================  ===================================  ==========================
kind                        text                                 detail
==========================  ===================================  ==========================
``"max_steps"``             ``max_steps``                        —
``"bound"``                 ``bound:<name>``                     the bounded record's name
``"ds_min"``                ``ds_min: <message>``                why the last step failed
``"jump failed"``           ``jump failed: <message>``           why the relocation failed
``"family ended"``          ``family ended: <message>``          where the starting mode's
                                                                 orbit lost the fundamental's
                                                                 majority (nothing beyond)
``"start failed"``          ``start failed: <message>``          why the first point failed
``"start outside bounds"``  ``start outside bounds``             —
``"interrupted"``           ``interrupted``                      —
==========================  ===================================  ==========================
"""

from __future__ import annotations

__all__ = ["Status"]


class Status(str):
    """A branch's terminal status: the text ``str(status)``, with ``kind`` and ``detail``.

    ``Status("bound", "amplitude") == "bound:amplitude"``; other kinds join kind and
    detail with ``": "``; a status without detail is its kind alone. Immutable, like the
    string it is.

    Parameters
    ----------
    kind : str
        What stopped the branch (see the module docstring).
    detail : str
        What the kind needs to be specific: the bound's name, a failure's message.
    cause : object, optional
        The structured reason behind the text, when the part that stopped the branch
        gives one (the family following: a :class:`mmshbm.family.end.FamilyEnd`, whose
        message the detail is); None otherwise. Not part of the text, nor of equality.
    """

    MAX_STEPS = "max_steps"
    BOUND = "bound"
    DS_MIN = "ds_min"
    JUMP_FAILED = "jump failed"
    FAMILY_ENDED = "family ended"
    START_FAILED = "start failed"
    START_OUTSIDE = "start outside bounds"
    INTERRUPTED = "interrupted"

    def __new__(cls, kind: str, detail: str = "", cause: object = None):
        kind, detail = str(kind), str(detail)
        if not detail:
            text = kind
        elif kind == cls.BOUND:
            text = f"{kind}:{detail}"
        else:
            text = f"{kind}: {detail}"
        return cls._make(text, kind, detail, cause)

    @classmethod
    def _make(cls, text: str, kind: str, detail: str, cause: object = None) -> Status:
        self = str.__new__(cls, text)
        self.__dict__["_kind"] = kind
        self.__dict__["_detail"] = detail
        self.__dict__["_cause"] = cause
        return self

    @classmethod
    def parse(cls, text: str) -> Status:
        """The status whose text is ``text``: kind the part before the first ``":"``,
        detail the rest (one leading space dropped). ``str(Status.parse(s)) == s`` for
        every string ``s``."""
        if isinstance(text, Status):
            return text
        text = str(text)
        kind, sep, rest = text.partition(":")
        if not sep:
            return cls._make(text, text, "")
        return cls._make(text, kind, rest[1:] if rest.startswith(" ") else rest)

    @classmethod
    def bound(cls, name: str) -> Status:
        """The branch reached the bound on the record ``name``."""
        return cls(cls.BOUND, name)

    @property
    def kind(self) -> str:
        return self.__dict__["_kind"]

    @property
    def detail(self) -> str:
        return self.__dict__["_detail"]

    @property
    def cause(self) -> object:
        """The structured reason behind the text (see the class docstring), or None."""
        return self.__dict__.get("_cause")

    def with_detail(self, more: str) -> Status:
        """The same kind, ``"; " + more`` appended to the detail (a rescue that failed too)."""
        return Status._make(f"{self}; {more}", self.kind, f"{self.detail}; {more}" if self.detail else more,
                            self.cause)

    def with_cause(self, cause: object) -> Status:
        """The same status with the structured reason ``cause``."""
        return Status._make(str(self), self.kind, self.detail, cause)

    def __setattr__(self, name, value):
        raise AttributeError("Status is immutable")

    def __reduce__(self):
        if self.cause is None:
            return (Status.parse, (str(self),))
        return (Status._make, (str(self), self.kind, self.detail, self.cause))

    def __str__(self) -> str:
        return str.__str__(self)
