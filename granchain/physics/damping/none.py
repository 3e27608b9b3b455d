"""No damping: the law's force alone (a scene without [damping])."""

from __future__ import annotations

from granchain.physics.damping.base import DampingPart


class NoDamping(DampingPart):
    """The contact force is the law's: nothing dissipated but by the law's own history."""

    name = "none"
