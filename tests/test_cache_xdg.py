"""The plugin cache follows XDG_CACHE_HOME (issue 43 item 7), under the same trust rules
(docs/security.md): GRANCHAIN_CACHE first, then $XDG_CACHE_HOME/granchain, then ~/.cache/granchain."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from granchain.lammps.cache import CacheError, cache_root, trusted_root


def test_the_cache_follows_xdg_cache_home(tmp_path):
    xdg = tmp_path / "xdg"
    assert cache_root({"XDG_CACHE_HOME": str(xdg)}) == xdg / "granchain"
    assert cache_root({"XDG_CACHE_HOME": str(xdg), "GRANCHAIN_CACHE": str(tmp_path / "own")}) == tmp_path / "own"


@pytest.mark.parametrize("value", ["", "relative/cache", "."])
def test_an_empty_or_relative_xdg_cache_home_is_ignored(value):
    """As the XDG specification says: a relative value names no directory of the user's."""
    assert cache_root({"XDG_CACHE_HOME": value}) == Path.home() / ".cache" / "granchain"


def test_an_xdg_cache_others_may_write_is_refused(tmp_path):
    """XDG_CACHE_HOME in a directory others may write (not sticky): the cache is refused, not used."""
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    with pytest.raises(CacheError, match="writable by others"):
        trusted_root(cache_root({"XDG_CACHE_HOME": str(shared)}))
