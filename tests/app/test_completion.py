"""Shell completion, in a real bash (and zsh when installed): the script is sourced and its function called with
the words a shell passes (COMP_WORDS/COMP_CWORD as readline splits them, or COMP_LINE/COMP_POINT)."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from gyrolab.app.completion import script
from tests.helpers import VISCOUS_DRAG

#: (words before the cursor, the word under it) -> candidates that must be offered, candidates that must not
CASES = [
    (["gyrolab", "integ"], {"integrator="}, {"integrator.rtol="}),
    (["gyrolab", "integrator="], {"integrator=taylor", "integrator=dop853", "integrator=rk4"}, {"integrator="}),
    (["gyrolab", "integrator", "=", "ta"], {"taylor"}, {"integrator=taylor"}),       # readline splits at =
    (["gyrolab", "integrator", "="], {"taylor", "rk4"}, set()),
    (["gyrolab", "b"], {"batch", "body="}, {"plot"}),
    (["gyrolab", "time.end=1", "b"], {"body="}, {"batch"}),                            # no subcommand after overrides
    (["gyrolab", "time."], {"time.end=", "time.start=", "time.n_output="}, {"time.", "time"}),
    (["gyrolab", "integrator."], {"integrator.rtol="}, set()),
    (["gyrolab", "output.figures="], {"output.figures=true", "output.figures=false"}, set()),
    (["gyrolab", "batch", "--s"], {"--scheduler"}, set()),
    (["gyrolab", "--batch", "body=lag"], {"body=lagrange_top"}, set()),
    (["gyrolab", "plot", "--an"], {"--animate"}, set()),
    (["gyrolab", "-m", "--conf"], {"--config-dir", "--config-name", "--config-path"}, set()),
    (["gyrolab", "completion", ""], {"bash", "zsh"}, set()),
    (["gyrolab", "hydra/launcher="], {"hydra/launcher=basic"}, set()),
    (["gyrolab", "hydra.s"], {"hydra.sweep."}, set()),
]


@pytest.fixture(scope="module")
def scripts(tmp_path_factory):
    folder = tmp_path_factory.mktemp("completion")
    for shell in ("bash", "zsh"):
        (folder / f"gyrolab.{shell}").write_text(script(shell))
    return folder


def _bash(scripts, words):
    words_text = " ".join(f"'{w}'" for w in words)
    program = (f"source {scripts / 'gyrolab.bash'}\nCOMP_WORDS=({words_text})\nCOMP_CWORD={len(words) - 1}\n"
               "_gyrolab\nprintf '%s\\n' \"${COMPREPLY[@]}\"\n")
    done = subprocess.run(["bash", "--norc", "--noprofile", "-c", program], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0 and not done.stderr, done.stderr
    return set(done.stdout.splitlines()) - {""}


@pytest.mark.parametrize("words, offered, not_offered", CASES, ids=[" ".join(c[0]) for c in CASES])
def test_bash_completes(words, offered, not_offered, scripts):
    candidates = _bash(scripts, words)
    assert offered <= candidates, candidates
    assert not (not_offered & candidates), candidates


def test_bash_completes_paths_for_plot(scripts, tmp_path, monkeypatch):
    (tmp_path / "results_dir").mkdir()
    monkeypatch.chdir(tmp_path)
    assert "results_dir" in _bash(scripts, ["gyrolab", "plot", "results_"])


def test_the_completion_is_registered_for_gyrolab(scripts):
    program = f"source {scripts / 'gyrolab.bash'}\ncomplete -p gyrolab\n"
    done = subprocess.run(["bash", "--norc", "-c", program], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "complete -F _gyrolab gyrolab"


@pytest.mark.skipif(shutil.which("zsh") is None, reason="zsh is not installed")
@pytest.mark.parametrize("line, offered", [("gyrolab integ", "integrator="), ("gyrolab integrator=ta", "integrator=taylor"),
                                           ("gyrolab b", "batch"), ("gyrolab batch --sch", "--scheduler")])
def test_zsh_completes(line, offered, scripts):
    """zsh runs the bash function through bashcompinit, which passes the whole line (COMP_LINE, not split at =)."""
    program = (f"source {scripts / 'gyrolab.zsh'}\nCOMP_LINE='{line}'; COMP_POINT=${{#COMP_LINE}}\n"
               "COMP_WORDS=(${=COMP_LINE}); COMP_CWORD=${#COMP_WORDS}\n_gyrolab\nprint -l -- $COMPREPLY\n")
    done = subprocess.run(["zsh", "-f", "-c", program], capture_output=True, text=True, timeout=60)
    assert offered in done.stdout.splitlines(), (done.stdout, done.stderr)


def test_hydras_spelling_prints_the_same_script(cli):
    done = cli("--shell-completion", "install=bash")
    assert done.returncode == 0, done.stderr
    # both from a fresh process: this one's plugin registry may hold what other tests registered in it
    own = cli("completion", "bash")
    assert own.returncode == 0, own.stderr
    assert done.stdout.strip() == own.stdout.strip() and "complete " in done.stdout
    refused = cli("--shell-completion", "install=fish")
    assert refused.returncode != 0 and "gyrolab completion bash" in refused.stderr


@pytest.mark.parametrize("line, offered", [("gyrolab integrator=ta", "taylor"), ("gyrolab -cd myconf b", "batch"),
                                           ("gyrolab batch time.", "time.end=")])
def test_bash_completes_from_the_line_readline_passes(line, offered, scripts):
    """Readline also passes the whole line and the cursor (COMP_LINE, COMP_POINT); the words are split at '='."""
    words = line.replace("=", " = ").split() if line.endswith("ta") else line.split()
    program = (f"source {scripts / 'gyrolab.bash'}\nCOMP_LINE='{line}'; COMP_POINT={len(line)}\n"
               f"COMP_WORDS=({' '.join(repr(w) for w in words)}); COMP_CWORD={len(words) - 1}\n"
               "_gyrolab\nprintf '%s\\n' \"${COMPREPLY[@]}\"\n")
    done = subprocess.run(["bash", "--norc", "-c", program], capture_output=True, text=True, timeout=60)
    assert offered in done.stdout.splitlines(), (done.stdout, done.stderr)


def test_bash_completes_option_values(scripts, tmp_path, monkeypatch):
    (tmp_path / "myconf").mkdir()
    (tmp_path / "myfile.txt").write_text("")
    monkeypatch.chdir(tmp_path)
    assert _bash(scripts, ["gyrolab", "--config-dir", "my"]) == {"myconf"}          # directories only
    assert _bash(scripts, ["gyrolab", "--cfg", ""]) == {"job", "hydra", "all"}
    assert _bash(scripts, ["gyrolab", "plot", "--format", ""]) == {"gif", "mp4"}
    assert "batch" in _bash(scripts, ["gyrolab", "--config-dir", "myconf", "b"])    # a value is not an override


def test_bash_completes_the_experiments_of_the_users_config_dir(scripts, tmp_path, monkeypatch):
    (tmp_path / "myconf" / "experiment").mkdir(parents=True)
    (tmp_path / "myconf" / "experiment" / "my_scan.yaml").write_text("# @package _global_\n")
    monkeypatch.chdir(tmp_path)
    for words in (["gyrolab", "--config-dir", "myconf", "experiment="], ["gyrolab", "-cd", "myconf", "-m", "experiment="],
                  ["gyrolab", "--config-dir=myconf", "batch", "experiment=my"]):
        candidates = _bash(scripts, words)
        assert "experiment=my_scan" in candidates, (words, candidates)
    assert "experiment=work_precision" in _bash(scripts, ["gyrolab", "-cd", "myconf", "experiment="])  # gyrolab's too
    assert "experiment=my_scan" not in _bash(scripts, ["gyrolab", "experiment="])   # only with that --config-dir


def test_the_script_offers_installed_plugins(tmp_path):

    from tests.conftest import installed_distribution

    with installed_distribution(tmp_path, "gyrolab-viscous-drag", "0.1.0",
                                {"viscous_drag": "gyrolab_viscous_drag:ViscousDrag"}, [VISCOUS_DRAG]):
        assert "force=viscous_drag" in script("bash").split("\n")
