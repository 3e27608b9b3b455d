"""A second local user against the Dask clusters granchain starts for a campaign (issue 40, item 1).

The user finds every port the campaign driver's user listens on (``/proc/net/tcp``, as anyone can)
and sends each a payload to run: ``Client(addr).run_on_scheduler`` and a worker's ``run`` handler,
over ``tcp://``, over ``tls://`` without credentials and over ``tls://`` with a certificate of its own
making. The payload would create a file only the driver's user can create; it must not appear. The
second user is made with ``useradd`` (root only) and removed after; elsewhere the tests skip with
the reason, but as root, or with GRANCHAIN_REQUIRE_SECURITY_USERS=1, a user that cannot be made is a
failure.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REQUIRED = os.environ.get("GRANCHAIN_REQUIRE_SECURITY_USERS") == "1" or (hasattr(os, "geteuid") and os.geteuid() == 0)

#: the second user's program: argv[1] the uid to attack, argv[2] the file its payload would create,
#: argv[3] the ports to attack (the test's own cluster's: other root processes of the machine are no
#: target of this test; the program checks that it could have found them in /proc/net/tcp)
ATTACKER = textwrap.dedent(
    """
    import asyncio, json, os, pickle, signal, sys, threading

    signal.alarm(120)  # a hang is the test's failure, not a stuck test

    uid, target, ports = int(sys.argv[1]), sys.argv[2], [int(p) for p in sys.argv[3].split(",")]

    def listening_ports():
        ports = set()
        for table in ("/proc/net/tcp", "/proc/net/tcp6"):
            try:
                rows = open(table).read().splitlines()[1:]
            except OSError:
                continue
            for row in rows:
                f = row.split()
                if f[3] == "0A" and int(f[7]) == uid:  # LISTEN, the victim's socket
                    ports.add(int(f[1].rsplit(":", 1)[1], 16))
        return sorted(ports)

    def payload(*args, **kwargs):
        open(target, "w").write("ran")

    from distributed import Client
    from distributed.core import rpc
    from distributed.security import Security

    modes = {"tcp": ("tcp", None), "tls-bare": ("tls", Security()), "tls-own-cert": ("tls", Security.temporary())}
    tried, ran = [], []
    visible = [p for p in listening_ports() if p in ports]  # what anyone reads in /proc/net/tcp

    def on_scheduler(addr, sec, mode):
        with Client(addr, timeout="3s", security=sec) as c:
            c.run_on_scheduler(payload)
            ran.append(f"{addr} run_on_scheduler ({mode})")

    def on_worker(addr, sec, mode):
        async def run_handler():
            r = rpc(addr, connection_args=(sec or Security()).get_connection_args("client"), timeout=3)
            try:
                await asyncio.wait_for(r.run(function=pickle.dumps(payload), args=pickle.dumps(())), 5)
            finally:
                await r.close_rpc()

        asyncio.run(run_handler())
        ran.append(f"{addr} run ({mode})")

    # each attempt in a thread of its own, given 20 s: one that hangs (a refused TLS handshake may)
    # has not run the payload, which the file it would create tells in the end
    threading.excepthook = lambda args: None  # a refused attempt raises: that is the point
    attempts = []
    for port in ports:
        for mode, (proto, sec) in modes.items():
            for attempt in (on_scheduler, on_worker):
                t = threading.Thread(target=attempt, args=(f"{proto}://127.0.0.1:{port}", sec, mode), daemon=True)
                t.start()
                attempts.append(t)
        tried.append(port)
    for t in attempts:
        t.join(20)
    print(json.dumps({"visible": visible, "tried": tried, "ran": ran}), flush=True)
    os._exit(0)  # not waiting for attempts that hang
    """
)


def _user_python(user: str) -> tuple[list[str], dict] | None:
    """A Python the second user can run that imports distributed: this one, or the system's of the
    same version with this environment's site-packages on its path; None if there is none."""
    import distributed

    site = str(Path(distributed.__file__).parent.parent)
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    env = {"PATH": "/usr/bin:/bin", "HOME": "/tmp", "PYTHONPATH": site, "PYTHONDONTWRITEBYTECODE": "1"}
    for candidate in (sys.executable, f"/usr/bin/python{version}", f"/usr/local/bin/python{version}"):
        cmd = ["runuser", "-u", user, "--", "env", "-i", *(f"{k}={v}" for k, v in env.items()), candidate]
        r = subprocess.run([*cmd, "-c", "import distributed"], capture_output=True, cwd="/", timeout=60)
        if r.returncode == 0:
            return cmd, env
    return None


def _unavailable(reason: str):
    if REQUIRED:
        pytest.fail(f"a second local user is required here (root or GRANCHAIN_REQUIRE_SECURITY_USERS=1): {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def second_user():
    """(the runuser command that starts the second user's Python, the user's name); the user is removed after."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        _unavailable("making a second local user needs root")
    for tool in ("useradd", "userdel", "runuser"):
        if shutil.which(tool) is None:
            _unavailable(f"{tool} is not on PATH")
    name = f"gcx{secrets.token_hex(4)}"
    r = subprocess.run(["useradd", "-M", "-N", "-s", "/usr/sbin/nologin", name], capture_output=True, text=True)
    if r.returncode != 0:
        _unavailable(f"useradd {name} failed: {r.stderr.strip()}")
    try:
        found = _user_python(name)
        if found is None:
            _unavailable(f"no Python that {name} may run imports distributed (this one is {sys.executable})")
        yield found[0], name
    finally:
        subprocess.run(["userdel", name], capture_output=True)


def _dask_ports(client) -> list[int]:
    """The ports of the cluster's Dask servers (scheduler, workers, nannies): where a message runs code.
    (Its HTTP routes, read-only, and other root processes of the machine are no target of this test.)"""
    info = client.scheduler_info()
    addresses = [info["address"]]
    for address, w in info["workers"].items():
        addresses += [address, w.get("nanny")]
    return sorted({_port(a) for a in addresses if a})


def _attack(second_user, tmp_path: Path, ports: list[int]) -> dict:
    """The second user's attack on these ports:
    {"visible": those it sees in /proc/net/tcp, "tried": ports, "ran": [what ran], "target_exists"}."""
    cmd, _ = second_user
    target = tmp_path / "private" / "payload-ran"  # where only this user (the payload, if it ran) can write
    target.parent.mkdir(mode=0o700)
    p = subprocess.Popen(
        [*cmd, "-c", ATTACKER, str(os.geteuid()), str(target), ",".join(map(str, ports))],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd="/",
        start_new_session=True,  # its own group: a hang is ended whole, and the user can be removed
    )
    try:
        stdout, stderr = p.communicate(timeout=300)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        raise
    r = subprocess.CompletedProcess(p.args, p.returncode, stdout, stderr)
    assert r.returncode == 0, r.stderr[-3000:]
    out = json.loads(r.stdout.strip().splitlines()[-1])
    out["target_exists"] = target.exists()
    return out


def _port(address: str) -> int:
    return int(address.rsplit(":", 1)[1])


def test_a_second_user_cannot_run_code_through_a_local_campaign_cluster(second_user, tmp_path):
    """The LocalCluster granchain's Executor starts for `campaign run --workers 1`: its scheduler,
    worker and nanny ports refuse the second user's payload on every protocol, and the driver's own
    client still runs tasks on its worker."""
    from granchain.campaigns.dask_executor import Executor

    ex = Executor(workers=1)
    try:
        client = ex.start()
        assert client.submit(sum, [1, 2]).result(timeout=60) == 3
        scheduler = _port(ex.cluster.scheduler_address)
        got = _attack(second_user, tmp_path, _dask_ports(client))
        assert len(got["tried"]) == 3  # the scheduler, the worker, its nanny
        assert scheduler in got["visible"], got  # found in /proc/net/tcp, as anyone can
        assert scheduler in got["tried"], got
        assert got["ran"] == [], got
        assert not got["target_exists"], got
        assert client.submit(sum, [2, 3]).result(timeout=60) == 5
    finally:
        ex.close()


FAKE_SBATCH = """#!/bin/sh
# records the job script it was given (its text and modes) and answers as sbatch does
cp "$1" "{capture}/job-$$.sh"
stat -c '%a %u' "$1" "$(dirname "$1")" > "{capture}/job-$$.modes"
echo "Submitted batch job 4242"
"""


def _fake_queue(tmp_path: Path, monkeypatch) -> Path:
    """sbatch and scancel on PATH that submit nothing; returns the directory where sbatch copies the scripts."""
    bin_dir, capture = tmp_path / "bin", tmp_path / "captured"
    bin_dir.mkdir()
    capture.mkdir()
    (bin_dir / "sbatch").write_text(FAKE_SBATCH.format(capture=capture))
    (bin_dir / "scancel").write_text("#!/bin/sh\nexit 0\n")
    for f in bin_dir.iterdir():
        f.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    return capture


def test_batch_jobs_scheduler_is_tls_and_its_keys_are_private(second_user, tmp_path, monkeypatch):
    """--cluster slurm: the scheduler the jobs connect to refuses the second user on every protocol;
    the job script sbatch receives sits, mode 0600, in a directory of mode 0700, holds no key, and
    names the key files (mode 0600, in that directory), which are gone when the campaign ends."""
    from granchain.campaigns import cluster as cl

    capture = _fake_queue(tmp_path, monkeypatch)
    jc = cl.JobCluster(cl.check(cl.ClusterSettings(kind="slurm", interface="lo")), 1, tmp_path / "ws" / "jobs")
    client = jc.start()
    try:
        assert jc.cluster.scheduler_address.startswith("tls://")
        got = _attack(second_user, tmp_path, [_port(jc.cluster.scheduler_address)])
        assert _port(jc.cluster.scheduler_address) in got["visible"], got
        assert got["ran"] == [], got
        assert not got["target_exists"], got
        (script,) = capture.glob("job-*.sh")
        text = script.read_text()
        file_mode, dir_mode = (line.split() for line in script.with_suffix(".modes").read_text().splitlines())
        assert file_mode == ["600", str(os.geteuid())]
        assert dir_mode == ["700", str(os.geteuid())]
        assert "PRIVATE KEY" not in text
        assert "BEGIN CERTIFICATE" not in text
        args = text.split()
        keys = [Path(args[args.index(flag) + 1]) for flag in ("--tls-key", "--tls-cert", "--tls-ca-file")]
        for key in keys:
            assert key.parent == jc.private
            assert stat.S_IMODE(key.stat().st_mode) == 0o600
            assert key.stat().st_uid == os.geteuid()
        assert stat.S_IMODE(jc.private.stat().st_mode) == 0o700
    finally:
        client.close()
        jc.close()
    assert not jc.private.exists()
