"""granchain submit: one big run on a batch queue (docs/clusters.md)."""

from __future__ import annotations


def add_submit_parser(sub) -> None:
    """granchain submit (not yet)."""
