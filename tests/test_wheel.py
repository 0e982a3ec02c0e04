"""The library outside the repository: a wheel built from it, installed in a fresh virtual environment,
used from another folder, has its tooling (``vgai_lite.lab``), its command line and the shipped
controllers (package data, ``book.shipped_file``)."""

import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_a_wheel_installed_in_a_fresh_venv_flies_the_shipped_vgai_from_another_folder(tmp_path):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(wheels),
                    str(ROOT)], check=True, cwd=tmp_path)
    (wheel,) = wheels.glob("vgai_lite-*.whl")
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=False)
    python = env_dir / "bin" / "python"
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    # the wheel itself into the new environment; its dependencies (torch, ...) from this one, read-only,
    # so that the test installs nothing from a registry (a path line in a .pth file runs no code of ours)
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True)
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    where = subprocess.run([str(python), "-c", "import vgai_lite, vgai_lite.lab.cli; from vgai_lite.book import "
                            "shipped_file; print(vgai_lite.__file__); print(shipped_file('vgai/vgai_F24.pt'))"],
                           capture_output=True, text=True, cwd=elsewhere)
    assert where.returncode == 0, where.stderr
    module, checkpoint = where.stdout.split()
    assert Path(module).is_relative_to(site) and Path(checkpoint).is_relative_to(site / "vgai_lite" / "shipped")
    run = subprocess.run([str(python), "-m", "vgai_lite", "evaluate", "--controller", "vgai_F24", "--episodes", "2"],
                         capture_output=True, text=True, cwd=elsewhere, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "vgai_F24" in run.stdout or "VGAI" in run.stdout
    assert "relative cost" in run.stdout and "over 2 episodes" in run.stdout
