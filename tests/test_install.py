"""Real installs: a read-only package folder with an unwritable home, a cache variable naming
a file, damaged cache files.  A cache never stops a solve (docs/robustness.md, "Real
installs")."""

from __future__ import annotations

import contextlib
import json
import os
import pickle
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from swarm_ik import paths
from swarm_ik.kernels import KERNEL_PACKAGES, cache_folders, drop_damaged_cache_files

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "swarm_ik"
_CACHED_KERNEL = re.compile(r"^\s*@numba\.n?jit\(.*cache=True", re.M)


def _env(**extra: str) -> dict[str, str]:
    """This process's environment without the cache variables and ``PYTHONPATH``."""
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("NUMBA_CACHE_DIR", "SWARM_IK_CACHE_DIR", "PYTHONPATH")
    }
    env.update(extra)
    return env


def _python(
    code: str, env: dict[str, str], cwd: Path | str, prefix: tuple[str, ...] = ()
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*prefix, sys.executable, "-c", code],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=900,
    )


def _cached_kernel_modules() -> list[str]:
    """The modules of swarm_ik defining a ``cache=True`` kernel."""
    out = []
    for f in sorted(PACKAGE.rglob("*.py")):
        if _CACHED_KERNEL.search(f.read_text()):
            parts = f.relative_to(ROOT).with_suffix("").parts
            out.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return out


# ------------------------------------------------------------------- where numba caches
def test_kernel_packages_name_every_folder_with_cached_kernels() -> None:
    folders = {".".join(m.split(".")[1:-1]) for m in _cached_kernel_modules()}
    assert folders and folders <= set(KERNEL_PACKAGES)


@pytest.fixture(scope="module")
def late_kernels() -> dict[str, str]:
    """For each module with cached kernels imported first in a fresh interpreter: the module
    that defined a ``cache=True`` kernel before ``swarm_ik.kernels`` was imported (the cache
    folder not settled yet), if any."""
    code = (
        "import importlib, json, sys, numba\n"
        "late, current = {}, None\n"
        "def watch(jit):\n"
        "    def wrapper(*args, **kwargs):\n"
        "        if kwargs.get('cache') and 'swarm_ik.kernels' not in sys.modules:\n"
        "            late.setdefault(current, sys._getframe(1).f_globals.get('__name__'))\n"
        "        return jit(*args, **kwargs)\n"
        "    return wrapper\n"
        "numba.njit, numba.jit = watch(numba.njit), watch(numba.jit)\n"
        "for current in json.loads(sys.argv[1]):\n"
        "    for name in [n for n in sys.modules if n.split('.')[0] == 'swarm_ik']:\n"
        "        del sys.modules[name]\n"
        "    importlib.import_module(current)\n"
        "print(json.dumps(late))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, json.dumps(_cached_kernel_modules())],
        env=_env(),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize(
    "module",
    _cached_kernel_modules(),
)
def test_cached_kernels_are_defined_after_the_cache_folder_is_settled(
    late_kernels: dict[str, str], module: str
) -> None:
    """swarm_ik.kernels chooses numba's cache folder on import: every module defining a
    ``cache=True`` kernel, imported first, must import it before its first kernel."""
    assert module not in late_kernels, f"{late_kernels[module]} defines a kernel before"


# ------------------------------------------------------- damaged numba cache files
TINY = "import numba\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1\nprint(f(41))\n"


@pytest.mark.parametrize("suffix", [".nbi", ".nbc"])
def test_a_truncated_numba_cache_file_is_removed_and_the_kernel_rebuilt(
    tmp_path: Path, suffix: str
) -> None:
    """numba (0.68) fails to load a truncated index or data file, on every run; the file
    removed (what ``import swarm_ik.kernels`` does), it compiles and saves the kernel anew."""
    (tmp_path / "tiny.py").write_text(TINY)
    cache = tmp_path / "cache"
    env = _env(NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(tmp_path))
    run = _python("import tiny", env, tmp_path)
    assert run.stdout.strip() == "42", run.stderr[-2000:]
    (f,) = cache.rglob(f"*{suffix}")
    whole = f.read_bytes()
    assert drop_damaged_cache_files([str(f.parent)]) == []  # intact files are kept

    f.write_bytes(whole[: len(whole) // 2])
    for _ in range(2):  # numba alone: the same failure on every run
        run = _python("import tiny", env, tmp_path)
        assert run.returncode != 0 and re.search("UnpicklingError|EOFError", run.stderr)

    assert drop_damaged_cache_files([str(f.parent)]) == [str(f)]
    run = _python("import tiny", env, tmp_path)
    assert run.stdout.strip() == "42", run.stderr[-2000:]
    assert f.read_bytes() and drop_damaged_cache_files([str(f.parent)]) == []

    # every truncation of the file is found (an .nbi cut after its version: numba fails too)
    f.write_bytes(whole)
    cut = tmp_path / "cut" / f.name
    cut.parent.mkdir()
    for k in range(0, len(whole), 1 if len(whole) < 4000 else 7):
        cut.write_bytes(whole[:k])
        assert drop_damaged_cache_files([str(cut.parent)]) == [str(cut)], k


KERNEL = "import numba\n@numba.njit(cache=True)\ndef f(x):\n    return x + 1\n"
LOADED = (
    "import kernel, swarm_ik.kernels as K\n"
    "K.cache_folders = lambda d: [{folder!r}]  # (this kernel's folder as swarm_ik's)\n"
    "print(K.loaded_despite_damage(lambda: kernel.f(41)))\n"
)


def test_a_cache_file_damaged_inside_is_removed_when_loading_fails(tmp_path: Path) -> None:
    """A data file whole in length but with flipped bytes: numba fails on every run (``LLVM
    bitcode parsing error``) and the check on import cannot see it; the first call that loads
    it (:func:`swarm_ik.kernels.loaded_despite_damage`) removes the cache files, says so in one
    line and compiles again; later runs load the new files.  An error of the call itself is
    raised as it is, and removes nothing."""
    (tmp_path / "kernel.py").write_text(KERNEL)
    cache = tmp_path / "cache"
    env = _env(NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(tmp_path))
    plain = "import kernel\nprint(kernel.f(41))\n"
    assert _python(plain, env, tmp_path).stdout.strip() == "42"
    (data,) = cache.rglob("*.nbc")
    damaged = bytearray(data.read_bytes())
    for k in range(len(damaged) // 2, len(damaged) // 2 + 64):
        damaged[k] ^= 0xFF
    data.write_bytes(bytes(damaged))
    for _ in range(2):  # numba alone: the same failure on every run
        assert _python(plain, env, tmp_path).returncode != 0
    code = LOADED.format(folder=str(data.parent))
    run = _python(code, env, tmp_path)
    assert run.returncode == 0 and run.stdout.strip() == "42", run.stderr[-2000:]
    (line,) = run.stderr.strip().splitlines()
    assert "loading the compiled kernels failed" in line and "compiling again" in line
    run = _python(plain, env, tmp_path)  # the new files load, nothing said
    assert run.returncode == 0 and run.stdout.strip() == "42" and not run.stderr.strip()

    files = sorted(p.name for p in data.parent.iterdir())
    bad = "import swarm_ik.kernels as K\nK.loaded_despite_damage(lambda: 1 / 0)\n"
    run = _python(bad, env, tmp_path)
    assert "ZeroDivisionError" in run.stderr and "loading the compiled" not in run.stderr
    assert sorted(p.name for p in data.parent.iterdir()) == files


def test_import_removes_damaged_swarm_ik_cache_files(tmp_path: Path) -> None:
    """``import swarm_ik.kernels`` checks the folder numba will load swarm_ik's kernels from
    and removes what is not whole, with one line on stderr."""
    cache = tmp_path / "numba"
    folder = Path(cache_folders(str(cache))[KERNEL_PACKAGES.index("kernels")])
    folder.mkdir(parents=True)
    damaged = folder / "lie.log3_nb-33.py311.nbi"
    damaged.write_bytes(b"\x80\x05\x95\x0a\x00\x00\x00\x00\x00\x00\x00\x8c\x06")
    run = _python("import swarm_ik.kernels", _env(NUMBA_CACHE_DIR=str(cache)), ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    assert not damaged.exists()
    (line,) = run.stderr.strip().splitlines()
    assert "removed 1 damaged numba cache file(s) (lie.log3_nb-33.py311.nbi)" in line


def test_import_clears_folders_and_files_in_the_wrong_places(tmp_path: Path) -> None:
    """A folder where a cache file should be is removed with the damaged files; a file where
    a module's cache folder should be is removed (numba would find no place to cache in:
    ``no locator available``, exit 3 on every run)."""
    cache = tmp_path / "numba"
    folders = [Path(f) for f in cache_folders(str(cache))]
    kernels_folder = folders[KERNEL_PACKAGES.index("kernels")]
    kernels_folder.mkdir(parents=True)
    (kernels_folder / "lie.log3_nb-33.py311.nbi").mkdir()
    goals_folder = folders[KERNEL_PACKAGES.index("goals")]
    goals_folder.write_text("")
    run = _python("import swarm_ik.kernels", _env(NUMBA_CACHE_DIR=str(cache)), ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    assert not (kernels_folder / "lie.log3_nb-33.py311.nbi").exists()
    assert not goals_folder.exists()
    (line,) = run.stderr.strip().splitlines()
    assert "removed 1 damaged numba cache file(s)" in line


# --------------------------------------------------------- swarm_ik's own cache folder
@pytest.fixture
def temp_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A private system temporary directory (where cache_dir falls back to)."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    monkeypatch.setattr(paths, "_PRIVATE_DIR", None)
    return tmp


def _unwritable_folders(tmp_path: Path) -> Iterator[Path]:
    """Folders no file can be created in: under a file, and (not as root) ``chmod 555``."""
    (tmp_path / "a_file").write_text("")
    yield tmp_path / "a_file"
    yield tmp_path / "a_file" / "cache"
    if hasattr(os, "geteuid") and os.geteuid() != 0:
        ro = tmp_path / "read_only"
        ro.mkdir(mode=0o555)
        yield ro


def test_cache_dir_falls_back_when_the_asked_folder_cannot_be_written(
    tmp_path: Path, temp_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    for bad in _unwritable_folders(tmp_path):
        monkeypatch.setenv("SWARM_IK_CACHE_DIR", str(bad))
        d = paths.cache_dir()
        assert d.parent == temp_dir and d.name.startswith("swarm_ik-cache")
        assert paths.writable_dir(d)


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX owners and modes")
def test_the_temporary_cache_folder_is_private(
    tmp_path: Path, temp_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Compiled code and pickles are loaded from the cache: the user's folder is made
    private (0o700), and one that is a link, or not the user's, is replaced by a fresh
    folder of the process."""
    (tmp_path / "a_file").write_text("")
    monkeypatch.setenv("SWARM_IK_CACHE_DIR", str(tmp_path / "a_file"))
    shared = temp_dir / f"swarm_ik-cache-{os.getuid()}"
    shared.mkdir()
    shared.chmod(0o777)
    assert paths.cache_dir() == shared and shared.stat().st_mode & 0o777 == 0o700

    shared.rmdir()
    (tmp_path / "elsewhere").mkdir()
    shared.symlink_to(tmp_path / "elsewhere")
    d = paths.cache_dir()
    assert d != shared and d.parent == temp_dir and paths.writable_dir(d)
    assert paths.cache_dir() == d  # one per process
    assert not list((tmp_path / "elsewhere").iterdir())


def test_sphere_and_pair_caches_with_the_cache_variable_at_a_file(
    get_robot, tmp_path: Path, temp_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import coal

    from swarm_ik.collision import RobotCollision
    from swarm_ik.spheres import fit_bodies

    (tmp_path / "a_file").write_text("")
    monkeypatch.setenv("SWARM_IK_CACHE_DIR", str(tmp_path / "a_file"))
    fits = fit_bodies([coal.Sphere(0.1), coal.Sphere(0.05)])
    rc = RobotCollision.from_robot(get_robot("ur5"), srdf=False, samples=20, seed=3)
    fallback = paths.cache_dir()
    assert fallback.parent == temp_dir
    assert len(list(fallback.glob("spheres-*.npz"))) == 1
    assert len(list(fallback.glob("pairs-*.json"))) == 1

    # damaged files there are misses (computed again, rewritten), not errors
    for f in fallback.glob("spheres-*.npz"):
        f.write_bytes(f.read_bytes()[:50])
    for f in fallback.glob("pairs-*.json"):
        f.write_bytes(b"\xff\xfe{not json")
    again = fit_bodies([coal.Sphere(0.1), coal.Sphere(0.05)])
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(fits, again, strict=True))
    rc2 = RobotCollision.from_robot(get_robot("ur5"), srdf=False, samples=20, seed=3)
    assert rc2.self_pairs == rc.self_pairs
    for f in fallback.glob("pairs-*.json"):
        json.loads(f.read_text())


def test_failed_cache_writes_are_skipped(
    get_robot, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cache folder that turned unwritable (a full disk, a read-only mount): the fit and the
    sampled pairs are returned, not an error."""
    import coal

    import swarm_ik.collision
    from swarm_ik.collision import RobotCollision
    from swarm_ik.spheres import fit_bodies

    (tmp_path / "a_file").write_text("")
    nowhere = tmp_path / "a_file" / "cache"
    monkeypatch.setattr(paths, "cache_dir", lambda: nowhere)
    monkeypatch.setattr(swarm_ik.collision, "cache_dir", lambda: nowhere)
    assert [len(r) for _, r in fit_bodies([coal.Sphere(0.1)])] == [1]
    rc = RobotCollision.from_robot(get_robot("ur5"), srdf=False, samples=20, seed=3)
    assert rc.pair_rule == "sampled"


def test_cli_solve_with_the_cache_variable_at_a_file(tmp_path: Path) -> None:
    (tmp_path / "a_file").write_text("")
    env = _env(SWARM_IK_CACHE_DIR=str(tmp_path / "a_file"), TMPDIR=str(tmp_path))
    q = ["0.1", "-0.5", "0.2", "0.3", "-0.2", "0.4", "0.1"]
    run = subprocess.run(
        [sys.executable, "-m", "swarm_ik.cli", "solve", "--robot", "yumi_left", "--from-q", *q],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "target reached" in run.stdout


# --------------------------------------------- a read-only install, an unwritable home
def _read_only_runner(folders: list[Path]) -> tuple[str, ...] | None:
    """The command prefix running a process that cannot write ``folders``: as a user, their
    permission bits (set here; the system's own folders are left alone); as root (who
    ignores them), a mount namespace where each is a read-only bind mount; ``None`` when
    neither is possible."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        for d in folders:
            if not d.is_relative_to(tempfile.gettempdir()) or d == Path(tempfile.gettempdir()):
                return None
            for sub, _dirs, files in os.walk(d):
                for name in files:
                    os.chmod(os.path.join(sub, name), 0o444)
            for sub, _dirs, _files in list(os.walk(d))[::-1]:
                os.chmod(sub, 0o555)
        return ()
    unshare = shutil.which("unshare")
    if unshare is None:
        return None
    mount = "mount --bind {0} {0} && mount -o remount,bind,ro {0}"
    script = " && ".join([mount.format(shlex.quote(str(d))) for d in folders] + ['exec "$@"'])
    prefix = (unshare, "--user", "--map-root-user", "--mount", "sh", "-c", script, "sh")
    probe = subprocess.run([*prefix, "touch", str(folders[0] / "probe")], capture_output=True)
    if probe.returncode == 0 or b"Read-only" not in probe.stderr:
        return None
    return prefix


def _restore(folders: list[Path]) -> None:
    """Folders made read-only by their permission bits writable again (for the clean-up)."""
    for d in folders:
        for sub, _dirs, _files in os.walk(d):
            with contextlib.suppress(OSError):
                os.chmod(sub, 0o755)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, Path]]:
    """The package copied as an install would lay it out (``robots/`` as
    ``swarm_ik/robots``, no ``__pycache__``) into ``site``, and an empty ``home``."""
    root = tmp_path_factory.mktemp("install")
    site, home = root / "site", root / "home"
    ignore = shutil.ignore_patterns("__pycache__")
    shutil.copytree(PACKAGE, site / "swarm_ik", ignore=ignore)
    shutil.copytree(ROOT / "robots", site / "swarm_ik" / "robots", ignore=ignore)
    home.mkdir()
    yield site, home
    _restore([site, home])


def _run_read_only(
    code: str, read_only: list[Path], env: dict[str, str], cwd: Path
) -> subprocess.CompletedProcess[str]:
    prefix = _read_only_runner(read_only)
    if prefix is None:
        pytest.skip("cannot make these folders read-only here")
    return _python(code, env, cwd, prefix)


SETTLE = (
    "import os, numba, swarm_ik.kernels\n"  # numba first, as most of swarm_ik's modules do
    "print(os.environ.get('NUMBA_CACHE_DIR'))\n"
    "print(numba.config.CACHE_DIR)\n"
)


@pytest.mark.parametrize("home_writable", [True, False])
@pytest.mark.parametrize("numba_dir", ["", "a_file"])
def test_read_only_package_gets_a_writable_numba_cache_folder(
    installed: tuple[Path, Path], tmp_path: Path, home_writable: bool, numba_dir: str
) -> None:
    """Where numba is told to cache (no compile here): the package read-only, with a
    writable home ``~/.cache/swarm_ik/numba`` silently; with an unwritable one the temporary
    fallback and one line; an unwritable ``NUMBA_CACHE_DIR`` replaced, with one line."""
    site, ro_home = installed
    home = tmp_path / "home" if home_writable else ro_home
    (tmp_path / "a_file").write_text("")
    (tmp_path / "tmp").mkdir()
    env = _env(HOME=str(home), TMPDIR=str(tmp_path / "tmp"), PYTHONPATH=str(site))
    env.pop("XDG_CACHE_HOME", None)
    if numba_dir:
        env["NUMBA_CACHE_DIR"] = str(tmp_path / numba_dir)
    run = _run_read_only(SETTLE, [site, ro_home], env, tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    asked = home / ".cache" / "swarm_ik"
    if home_writable:
        want = asked / "numba"
    else:
        (fallback,) = (tmp_path / "tmp").glob("swarm_ik-cache-*")
        want = fallback / "numba"
    assert run.stdout.split() == [str(want), str(want)]
    lines = run.stderr.strip().splitlines()
    if numba_dir:
        assert lines == [
            f"swarm_ik: NUMBA_CACHE_DIR {str(tmp_path / numba_dir)!r} cannot be written; "
            f"numba's compiled kernels are cached in {want}"
        ]
    elif home_writable:
        assert lines == []
    else:
        assert lines == [
            f"swarm_ik: neither the package's folder nor {asked} can be written; numba's "
            f"compiled kernels are cached in {want} (set SWARM_IK_CACHE_DIR to keep them "
            "elsewhere)"
        ]


def test_nothing_writable_says_which_variable_to_set(
    installed: tuple[Path, Path], tmp_path: Path
) -> None:
    """Not even a temporary folder can be written (root only: /tmp made read-only in a
    mount namespace): one line before numba's own refusal."""
    site, home = installed
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("needs root, to make the system's temporary folders read-only")
    tmps = [Path(p) for p in ("/tmp", "/var/tmp", "/usr/tmp") if Path(p).is_dir()]
    env = _env(HOME=str(home), PYTHONPATH=str(site))
    env.pop("XDG_CACHE_HOME", None)
    env.pop("TMPDIR", None)
    run = _run_read_only(SETTLE, [site, home, *tmps], env, site)
    assert run.stderr.startswith(
        "swarm_ik: no folder can be written for numba's compiled kernels"
    ), run.stderr[-2000:]
    assert "set NUMBA_CACHE_DIR to a writable folder" in run.stderr.splitlines()[0]


SOLVE = (
    "import swarm_ik\n"
    "r = swarm_ik.load_robot('yumi_left')\n"
    "p = swarm_ik.IKProblem.from_q(r, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])\n"
    "print(swarm_ik.__file__)\n"
    "print(swarm_ik.solve(p, seed=0).success)\n"
    "from swarm_ik.cli import main\n"
    "print(main(['solve', '--robot', 'yumi_left', '--from-q', "
    "'0.1', '-0.5', '0.2', '0.3', '-0.2', '0.4', '0.1']))\n"
)


@pytest.mark.slow
def test_read_only_install_with_unwritable_home_solves(
    installed: tuple[Path, Path], tmp_path: Path
) -> None:
    """The package in a folder that cannot be written, HOME and XDG_CACHE_HOME unwritable,
    no NUMBA_CACHE_DIR: a solve (and ``swarm-ik solve``) compiles numba's kernels into
    swarm_ik's temporary fallback folder, with one line saying so.  Then two of those cache
    files truncated: the next run removes them, says so, and solves.  (One cold compile.)"""
    site, home = installed
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = _env(
        HOME=str(home),
        XDG_CACHE_HOME=str(home / ".cache"),
        TMPDIR=str(tmp),
        PYTHONPATH=str(site),
        PYTHONDONTWRITEBYTECODE="1",
    )
    first = _run_read_only(SOLVE, [site, home], env, tmp_path)
    assert first.returncode == 0, first.stderr[-3000:]
    lines = first.stdout.strip().splitlines()
    assert lines[:2] == [str(site / "swarm_ik" / "__init__.py"), "True"]  # the solve
    assert "target reached" in first.stdout and lines[-1] == "0"  # the CLI's exit code
    assert "no locator" not in first.stderr
    numba_dir = next(tmp.glob("swarm_ik-cache-*")) / "numba"
    notice = [ln for ln in first.stderr.splitlines() if ln.startswith("swarm_ik: ")]
    assert notice[0] == (
        f"swarm_ik: neither the package's folder nor {home / '.cache' / 'swarm_ik'} can be "
        f"written; numba's compiled kernels are cached in {numba_dir} (set "
        "SWARM_IK_CACHE_DIR to keep them elsewhere)"
    )
    assert not list(site.rglob("__pycache__"))

    nbi = sorted(numba_dir.rglob("*.nbi"))[0]
    nbc = sorted(numba_dir.rglob("*.nbc"))[-1]
    for f in (nbi, nbc):
        f.write_bytes(f.read_bytes()[: f.stat().st_size // 2])
    second = _run_read_only(SOLVE, [site, home], env, tmp_path)
    assert second.returncode == 0, second.stderr[-3000:]
    lines = second.stdout.strip().splitlines()
    assert lines[1] == "True" and lines[-1] == "0"
    assert "removed 2 damaged numba cache file(s)" in second.stderr
    assert drop_damaged_cache_files({str(nbi.parent), str(nbc.parent)}) == []


def test_a_users_goal_kernel_that_cannot_be_cached_removes_nothing(tmp_path: Path) -> None:
    """A goal kernel of the user's that numba cannot cache (defined in a script read from
    stdin: no file) is compiled without a cache (it was refused as "does not compile");
    swarm_ik's own cache files are left where they are (the recovery is for swarm_ik's
    kernels)."""
    cache = tmp_path / "numba"
    folder = Path(cache_folders(str(cache))[KERNEL_PACKAGES.index("kernels")])
    folder.mkdir(parents=True)
    kept = folder / "lie.log3_nb-33.py311.nbi"
    kept.write_bytes(pickle.dumps(1) + pickle.dumps({}))
    script = (
        "import numba\n"
        "from swarm_ik.goals import kernel_slot\n"
        "from swarm_ik.errors import InvalidArgumentError\n"
        "@numba.njit\n"
        "def mine(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):\n"
        "    res[0] = q[0]\n"
        "try:\n"
        "    print('slot', kernel_slot(mine))\n"
        "except InvalidArgumentError as exc:\n"
        "    print('refused', exc)\n"
    )
    run = subprocess.run(
        [sys.executable, "-"], input=script, env=_env(NUMBA_CACHE_DIR=str(cache)),
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert run.stdout.startswith("slot"), (run.stdout, run.stderr[-2000:])
    assert kept.exists() and "removed" not in run.stderr


def test_an_interruption_is_no_damaged_cache() -> None:
    """What a Ctrl-C leaves while kernels load (a ``SystemError`` of a C routine cut short, an
    error raised while a ``KeyboardInterrupt`` was handled) never has the cache removed."""
    from swarm_ik.kernels import cut_by_ctrl_c

    assert cut_by_ctrl_c(SystemError("null argument to internal routine"))
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise RuntimeError("LLVM bitcode parsing error") from None
    except RuntimeError as exc:
        assert cut_by_ctrl_c(exc)  # (its context, though not its cause, is the interruption)
    assert not cut_by_ctrl_c(RuntimeError("LLVM bitcode parsing error"))


def _whole_index(folder: Path) -> Path:
    """A cache index file that is whole (two pickles), as numba writes them."""
    folder.mkdir(parents=True, exist_ok=True)
    index = folder / "lie.log3_nb-33.py311.nbi"
    index.write_bytes(pickle.dumps(1) + pickle.dumps(2))
    return index


def test_a_process_that_aborts_while_loading_kernels_makes_the_next_one_clear_the_cache(
    tmp_path: Path,
) -> None:
    """An abort inside LLVM (a cache file damaged so that its bitcode reader fails an
    assertion) kills the process where no Python handler sees it; the mark it leaves makes
    the next import remove every cache file (one line), so that only one run aborts."""
    cache = tmp_path / "numba"
    index = _whole_index(Path(cache_folders(str(cache))[KERNEL_PACKAGES.index("kernels")]))
    env = _env(NUMBA_CACHE_DIR=str(cache))
    aborted = _python(
        "import os, swarm_ik.kernels as k\nwith k.loading_marked():\n    os.abort()", env, ROOT
    )
    assert aborted.returncode != 0 and index.exists()
    run = _python("import swarm_ik.kernels", env, ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    assert not index.exists()
    (line,) = run.stderr.strip().splitlines()
    assert "a process died while it loaded the compiled kernels" in line
    assert "removed 1 numba cache file(s)" in line
    again = _python("import swarm_ik.kernels", env, ROOT)  # (the mark went with the files)
    assert again.returncode == 0 and again.stderr == ""


def test_a_load_that_returns_or_raises_leaves_no_mark_and_a_live_ones_mark_is_kept(
    tmp_path: Path,
) -> None:
    """A load that ends (or raises: a Ctrl-C, an error) removes its mark, nested loads
    included; the mark of a process still loading (another solve starting beside this one)
    clears nothing."""
    cache = tmp_path / "numba"
    index = _whole_index(Path(cache_folders(str(cache))[KERNEL_PACKAGES.index("kernels")]))
    env = _env(NUMBA_CACHE_DIR=str(cache))
    code = (
        "import os, swarm_ik.kernels as k\n"
        "with k.loading_marked():\n"
        "    with k.loading_marked():\n"
        "        pass\n"
        "    print(len([n for n in os.listdir(k.cache_folders(k._SETTLED[0])[0])"
        " if n.startswith(k.LOADING_MARK)]))\n"
        "try:\n"
        "    k.loaded_despite_damage(lambda: 1 / 0, mark=True)\n"
        "except ZeroDivisionError:\n"
        "    pass\n"
    )
    run = _python(code, env, ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split() == ["1"]  # (one mark while inside, the nested one the same)
    first = Path(cache_folders(str(cache))[0])
    assert not [p for p in first.iterdir() if p.name.startswith("swarm_ik-loading")]
    live = first / f"swarm_ik-loading-{platform.node()}-{os.getpid()}"
    live.write_text("")
    run = _python("import swarm_ik.kernels", env, ROOT)
    assert run.returncode == 0 and run.stderr == "" and index.exists() and live.exists()
