"""Reading and writing inside a directory someone else may have prepared: run directories, workspaces
and collect directories are shared, so no symlink or name in them may make granchain read or write
outside them."""

from __future__ import annotations
