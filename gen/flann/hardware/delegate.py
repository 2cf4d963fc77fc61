"""A spec's read-only attributes that are another record's, under the spec's own names."""

from __future__ import annotations

from operator import attrgetter


def delegated(path: str) -> property:
    """The attribute at ``path`` (dotted, from the spec: ``"front.model"``, ``"temp.bits"``)."""
    return property(attrgetter(path), doc=f"``{path}``")
