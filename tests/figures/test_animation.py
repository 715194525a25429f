"""``gyrolab --plot --animate PATH`` and ``gyrolab.figures.animation.animate`` on a short run.

The attitude the animation draws is checked against the run's own Euler angles (z-x-z: the body z axis in the
fixed frame is (sin θ sin ψ, −sin θ cos ψ, cos θ)), which gyrolab computes by a different route (from α and γ
through the angles), so a transposed or mislabelled rotation fails here.
"""

from __future__ import annotations

import shutil
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

pytest.importorskip("PIL")
from PIL import Image  # noqa: E402

from gyrolab import run  # noqa: E402
from gyrolab.errors import ConfigError  # noqa: E402
from gyrolab.figures.animation import MAX_FRAMES, animate, attitude, frame_indices, motion_figure  # noqa: E402
from gyrolab.output.dataset import write_dataset  # noqa: E402

SHORT = ["time.end=3", "time.n_output=31", "initial.r0=2", "output.figures=false"]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    directory = tmp_path_factory.mktemp("run")
    write_dataset(run(SHORT), directory / "run.nc")
    return directory


def _frames(path) -> int:
    with Image.open(path) as image:
        assert image.format == "GIF"
        return image.n_frames


def test_gif_has_the_frames_asked_for(run_dir, tmp_path):
    out = animate(run_dir, output=tmp_path / "motion.gif", frames=12, fps=10)
    assert out == tmp_path / "motion.gif" and out.read_bytes()[:6] == b"GIF89a"
    assert _frames(out) == 12
    assert [p.name for p in tmp_path.iterdir()] == ["motion.gif"]       # no temporary left beside it


def test_default_output_beside_the_run_and_no_more_frames_than_output_times(run_dir):
    out = animate(run_dir / "run.nc", frames=100)
    assert out == run_dir / "figures" / "animation.gif"
    assert _frames(out) == 31                                             # the run has 31 output times


def test_every_frame_is_titled_with_its_time(run_dir):
    ds = xr.load_dataset(run_dir / "run.nc")
    indices = frame_indices(ds.sizes["time"], 7)
    assert indices[0] == 0 and indices[-1] == 30 and len(indices) == 7
    fig, update = motion_figure(ds, indices)
    for k, i in enumerate(indices):
        update(k)
        title = fig._suptitle.get_text()
        assert f"t = {ds.time.values[i]:.3f} (units of 1/c)" in title, title


def test_the_attitude_drawn_is_the_runs_rotation(run_dir):
    ds = xr.load_dataset(run_dir / "run.nc")
    rotation, _, down, _ = attitude(ds)
    assert down                                                           # fixed Z along the weight
    eye = np.einsum("kij,kil->kjl", rotation, rotation)
    np.testing.assert_allclose(eye, np.broadcast_to(np.eye(3), eye.shape), atol=1e-8)
    np.testing.assert_allclose(np.linalg.det(rotation), 1.0, atol=1e-8)  # a rotation, not a reflection
    psi, theta = ds.psi.values, ds.theta.values
    apex = np.stack([np.sin(theta) * np.sin(psi), -np.sin(theta) * np.cos(psi), np.cos(theta)], axis=1)
    np.testing.assert_allclose(rotation[:, :, 2], apex, atol=1e-8)


def test_gyrostat_is_animated_in_its_orbital_frame(tmp_path):
    ds = run(["experiment=gyrostat", "time.end=1", "time.n_output=11", "output.figures=false"])
    rotation, names, down, what = attitude(ds)
    assert not down and "orbit normal" in names and "orbital" in what
    np.testing.assert_allclose(rotation[:, :, 2], ds.body_axis_orbital.values, atol=1e-8)
    write_dataset(ds, tmp_path / "run.nc")
    assert _frames(animate(tmp_path, frames=5)) == 5


@pytest.mark.parametrize("kwargs, words", [
    ({"fmt": "avi"}, "not one of gif, mp4"),
    ({"frames": 1}, "from 2 to"),
    ({"frames": MAX_FRAMES + 1}, "from 2 to"),
    ({"fps": 0}, "frames per second"),
])
def test_bad_options_are_one_sentence_and_leave_no_file(run_dir, tmp_path, kwargs, words):
    with pytest.raises(ConfigError, match=words):
        animate(run_dir, output=tmp_path / "x.gif", **kwargs)
    assert not list(tmp_path.iterdir())


def test_a_run_without_the_full_attitude_is_refused(tmp_path):
    write_dataset(run([*SHORT, "output.euler_angles=false"]), tmp_path / "run.nc")
    with pytest.raises(ConfigError, match="output.euler_angles=true"):
        animate(tmp_path)
    assert not (tmp_path / "figures").exists() or not list((tmp_path / "figures").iterdir())


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not on PATH")
def test_mp4_with_ffmpeg(run_dir, tmp_path):
    out = animate(run_dir, output=tmp_path / "motion.mp4", fmt="mp4", frames=8)
    assert out.stat().st_size > 0 and out.read_bytes()[4:8] == b"ftyp"


def test_command_line_end_to_end(run_dir, tmp_path):
    out = tmp_path / "cli.gif"
    done = subprocess.run([sys.executable, "-m", "gyrolab", "--plot", "--animate", str(run_dir), "--frames", "6",
                           "--fps=12", f"--output={out}"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert _frames(out) == 6
    bad = subprocess.run([sys.executable, "-m", "gyrolab", "--plot", "--animate", str(run_dir), "--format=webm"],
                         capture_output=True, text=True, timeout=300)
    lines = bad.stderr.strip().splitlines()
    assert bad.returncode != 0 and len(lines) == 1 and lines[0].startswith("gyrolab: error:"), bad.stderr
    assert all(word in lines[0] for word in ("webm", "gif", "mp4"))


@pytest.mark.parametrize("args, words", [
    (["--bogus", "3"], "--bogus"),
    (["--frames", "2.5"], "2.5"),
    (["--fps=fast"], "fast"),
    (["second_path"], "second_path"),
])
def test_command_line_refusals_are_one_sentence(run_dir, tmp_path, args, words):
    done = subprocess.run([sys.executable, "-m", "gyrolab", "plot", "--animate", str(run_dir), *args],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode != 0 and len(lines) == 1 and lines[0].startswith("gyrolab: error:"), done.stderr
    assert words in lines[0] and "Traceback" not in done.stderr
    assert not list(tmp_path.iterdir())
