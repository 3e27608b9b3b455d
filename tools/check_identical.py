"""Check that a refactoring changed no deck and no output: the tree at a base revision against a tree.

Usage::

    python tools/check_identical.py BASE_REV [--tree DIR] [--generated N] [--runs M] [--no-runs]

For the tree at BASE_REV (a ``git archive`` snapshot) and for DIR (default: this checkout's working
tree), each in its own interpreter with PYTHONPATH set to that tree, it

* renders the LAMMPS deck and data file of every bundled scene and of N generated scenes (drawn once,
  deterministically, from ``tests/scenegen.scene_texts`` of DIR, and fed to both trees as text), and
* runs ``granchain run --backend reference`` on every bundled scene and on M of the generated ones,
  and compares every file of the run directories; in ``summary.json`` the wall-clock keys
  (``wall_time``, ``price``, ``provenance``, ``companion_wall_time``, ``overhead``) are left out:
  they are measured, not computed.

It prints each difference and exits 1 if there is one. A scene that one tree refuses and the other
accepts is a difference; one both refuse with the same message is not.
"""

from __future__ import annotations

import argparse
import difflib
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

#: summary.json keys whose values are measured on the wall clock
CLOCK_KEYS = {"wall_time", "price", "provenance", "companion_wall_time", "overhead"}

RENDER = r"""
import json, sys, traceback
from pathlib import Path
from granchain.exceptions import GranchainError
from granchain.scene import bundled_scenes, load_scene, parse_scene
from granchain.templates import render_deck
from granchain.workflows.plan import plan_scene
out = Path(sys.argv[1]); texts = json.loads(Path(sys.argv[2]).read_text())
cases = [(n, lambda n=n: load_scene(n)) for n in bundled_scenes()]
cases += [(f"generated-{i:03d}", lambda t=t: parse_scene(t)) for i, t in enumerate(texts)]
for name, load in cases:
    try:
        sc = load()
        if sc.needs_plan:
            sc = plan_scene(sc).scene
        d = render_deck(sc)
        (out / f"{name}.lmp").write_text(d.deck); (out / f"{name}.data").write_text(d.data)
    except GranchainError as e:
        (out / f"{name}.refused").write_text(str(e))
"""


def generated_texts(n: int, tree: Path) -> list[str]:
    """n scene texts from tests/scenegen, the same on every call (derandomized hypothesis)."""
    if n == 0:
        return []
    sys.path[:0] = [str(tree)]
    from hypothesis import given, settings

    from tests.scenegen import scene_texts

    texts: list[str] = []

    @settings(derandomize=True, database=None, max_examples=n, deadline=None)
    @given(t=scene_texts(max_beads=40))
    def collect(t):
        texts.append(t)

    collect()
    return texts[:n]


def snapshot(rev: str, repo: Path, dest: Path) -> Path:
    """The tree at rev, extracted under dest."""
    tar = dest / "base.tar"
    subprocess.run(["git", "-C", str(repo), "archive", "-o", str(tar), rev], check=True)
    tree = dest / "base"
    with tarfile.open(tar) as t:
        t.extractall(tree, filter="data")
    return tree


def produce(tree: Path, out: Path, texts_file: Path, run_names: list[tuple[str, str]]) -> None:
    """Decks and reference run directories of `tree` under out."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    decks = out / "decks"
    decks.mkdir(parents=True)
    subprocess.run([sys.executable, "-c", RENDER, str(decks), str(texts_file)], env=env, check=True, cwd=tree)
    for name, source in run_names:
        r = subprocess.run(
            [
                sys.executable,
                "-m",
                "granchain",
                "run",
                source,
                "--backend",
                "reference",
                "--quiet",
                "--out",
                str(out / "runs" / name),
            ],
            env=env,
            cwd=tree,
            capture_output=True,
            text=True,
        )
        (out / "runs").mkdir(exist_ok=True)
        (out / "runs" / f"{name}.exit").write_text(f"{r.returncode}\n{r.stderr if r.returncode else ''}")


def _strip(obj):
    if isinstance(obj, dict):
        return {k: _strip(v) for k, v in obj.items() if k not in CLOCK_KEYS}
    if isinstance(obj, list):
        return [_strip(v) for v in obj]
    return obj


def differences(a: Path, b: Path) -> list[str]:
    """Every file that differs between the two output trees (summary.json without its clock keys)."""
    out = []
    fa = {p.relative_to(a) for p in a.rglob("*") if p.is_file()}
    fb = {p.relative_to(b) for p in b.rglob("*") if p.is_file()}
    for rel in sorted(fa ^ fb):
        out.append(f"only in {'base' if rel in fa else 'tree'}: {rel}")
    for rel in sorted(fa & fb):
        x, y = (a / rel).read_bytes(), (b / rel).read_bytes()
        if rel.name == "summary.json":
            x = json.dumps(_strip(json.loads(x)), sort_keys=True, indent=1).encode()
            y = json.dumps(_strip(json.loads(y)), sort_keys=True, indent=1).encode()
        if x != y:
            diff = difflib.unified_diff(
                x.decode(errors="replace").splitlines(), y.decode(errors="replace").splitlines(), lineterm="", n=1
            )
            out.append(f"differs: {rel}\n" + "\n".join(list(diff)[:12]))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base", help="the base revision (git rev)")
    ap.add_argument("--tree", type=Path, default=Path(__file__).resolve().parents[1])
    ap.add_argument("--generated", type=int, default=40, help="generated scenes to render (default 40)")
    ap.add_argument("--runs", type=int, default=6, help="generated scenes also run on the reference (default 6)")
    ap.add_argument("--no-runs", action="store_true", help="decks only")
    args = ap.parse_args()
    tree = args.tree.resolve()
    with tempfile.TemporaryDirectory(prefix="granchain-identical-") as tmp:
        tmp = Path(tmp)
        base = snapshot(args.base, tree, tmp)
        texts = generated_texts(args.generated, tree)
        texts_file = tmp / "texts.json"
        texts_file.write_text(json.dumps(texts))
        runs: list[tuple[str, str]] = []
        if not args.no_runs:
            sys.path[:0] = [str(tree)]
            from granchain.scene import bundled_scenes

            runs = [(n, n) for n in bundled_scenes()]
            for i, t in enumerate(texts[: args.runs]):
                p = tmp / f"generated-{i:03d}.toml"
                p.write_text(t)
                runs.append((p.stem, str(p)))
        produce(base, tmp / "out-base", texts_file, runs)
        produce(tree, tmp / "out-tree", texts_file, runs)
        diffs = differences(tmp / "out-base", tmp / "out-tree")
        n_decks = len(list((tmp / "out-tree" / "decks").glob("*")))
        print(
            f"compared {n_decks} deck/data/refusal files and {len(runs)} reference runs "
            f"({len(texts)} generated scenes): {len(diffs)} differences"
        )
        for d in diffs:
            print(d)
        return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
