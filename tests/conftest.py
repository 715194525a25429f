import contextlib
import os

import pytest

from tests.helpers import gyrolab


@pytest.fixture
def cli(tmp_path):
    """Run the real ``gyrolab`` command in a subprocess (cwd = tmp_path)."""
    def _run(*args, env_extra=None):
        return gyrolab(*args, cwd=tmp_path, env={**os.environ, **(env_extra or {})})

    return _run


@contextlib.contextmanager
def installed_distribution(site, name, version, plugins=None, paths=(), group="gyrolab.forces", *, forces=None):
    """A distribution laid out the way pip does it: ``site``/NAME-VERSION.dist-info with entry points ``plugins``
    (dict name -> "module:Class") in the entry-point ``group`` (``gyrolab.forces`` unless given: ``gyrolab.integrators``,
    ...; or ``plugins`` as a dict group -> {name: "module:Class"} for several groups), ``site`` and ``paths`` on
    sys.path, gyrolab's plugin registry refreshed on entry and on exit. ``forces=`` is the older name of
    ``plugins``."""
    from gyrolab.contracts import registry
    from gyrolab.engine import config

    plugins = forces if plugins is None else plugins
    groups = plugins if plugins and all(isinstance(v, dict) for v in plugins.values()) else {group: plugins}
    info = site / f"{name.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    (info / "entry_points.txt").write_text("".join(
        f"[{g}]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items()) for g, entries in groups.items()))
    mp = pytest.MonkeyPatch()
    for path in (*paths, site):
        mp.syspath_prepend(str(path))
    registry.external.cache_clear()
    config.register_plugin_configs.cache_clear()
    try:
        yield site
    finally:
        mp.undo()
        registry.external.cache_clear()
        config.register_plugin_configs.cache_clear()


@contextlib.contextmanager
def mounted_tmpfs(directory, size):
    """A tmpfs of ``size`` (e.g. "256k") mounted at a new ``directory`` for a really full disk (needs root and
    mount(8)); the test is skipped where it cannot be mounted."""
    import subprocess

    directory.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    try:
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(directory)],
                              capture_output=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        pytest.skip("mount(8) is not available")
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        yield directory
    finally:
        subprocess.run(["umount", "-l", str(directory)], capture_output=True, timeout=10)
