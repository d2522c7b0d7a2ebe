"""The package: its name on the index, its version written once and shown everywhere, its
license, citation and changelog, and a wheel that installs and runs without the checkout."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest
import tomllib
import yaml

import atlas
from tests.helpers import REPO

PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())


def test_the_distribution_is_pendulum_atlas_with_the_command_atlas():
    """``pip install atlas`` installs an unrelated project: the distribution has its own
    name, the import and the command stay ``atlas``."""
    project = PYPROJECT["project"]
    assert project["name"] == "pendulum-atlas"
    assert project["scripts"] == {"atlas": "atlas.cli:entry"}
    assert PYPROJECT["tool"]["setuptools"]["packages"]["find"]["include"] == ["atlas*"]


def test_the_version_is_written_once():
    """pyproject takes the version from atlas/_version.py (no second copy to forget), and
    atlas.__version__ is that one; it is a release number (PEP 440, X.Y.Z)."""
    assert "version" not in PYPROJECT["project"]
    assert "version" in PYPROJECT["project"]["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "atlas._version.__version__"}
    assert re.fullmatch(r"\d+\.\d+\.\d+", atlas.__version__)
    written = re.findall(r"\b\d+\.\d+\.\d+\b", (REPO / "atlas" / "_version.py").read_text())
    assert written == [atlas.__version__]


def test_files_record_the_version():
    from atlas.pipeline.identity import library_versions

    assert library_versions()["atlas_version"] == atlas.__version__


def test_license_is_mit_in_every_place_that_says_so():
    text = (REPO / "LICENSE").read_text()
    assert text.startswith("MIT License") and "Permission is hereby granted" in text
    assert PYPROJECT["project"]["license"] == "MIT"
    assert PYPROJECT["project"]["license-files"] == ["LICENSE"]
    assert yaml.safe_load((REPO / "CITATION.cff").read_text())["license"] == "MIT"


def test_citation_is_cff_1_2_0_of_this_version():
    """CITATION.cff parses and has what CFF 1.2.0 requires (cff-version, message, title,
    authors, each a person with family-names or an entity with a name) and the package's
    version; a date-released in ISO form (YAML must not turn it into a date object: CFF's
    schema asks for a string)."""
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    assert cff["message"].strip() and cff["title"].strip() and cff["type"] == "software"
    assert cff["authors"] and all(a.get("family-names") or a.get("name")
                                  for a in cff["authors"])
    assert cff["version"] == atlas.__version__
    assert isinstance(cff["date-released"], str)
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", cff["date-released"])


def test_changelog_has_a_section_for_this_version():
    text = (REPO / "CHANGELOG.md").read_text()
    assert text.startswith("# Changelog")
    assert re.search(rf"^## \[{re.escape(atlas.__version__)}\] - \d{{4}}-\d{{2}}-\d{{2}}$",
                     text, re.M)


# ----------------------------------------------------------------------- the wheel

def _source_tree(destination: Path) -> Path:
    """What a source distribution holds (the package, pyproject, README, LICENSE), copied
    without caches: the wheel is built from it, not from the checkout in place (which would
    leave build/ and an egg-info in the repository)."""
    shutil.copytree(REPO / "atlas", destination / "atlas",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(REPO / name, destination / name)
    return destination


def _run(args: list, **kwargs) -> subprocess.CompletedProcess:
    done = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    assert done.returncode == 0, f"{args}: {done.stdout}\n{done.stderr}"
    return done


def _venv_with_these_dependencies(venv: Path) -> tuple[Path, Path]:
    """A new venv without pip whose dependencies are this venv's site-packages, after its own
    (a path in a .pth file is appended to sys.path; that folder's own .pth files, such as an
    editable install's that points at the checkout, are not processed): the venv and its
    site-packages."""
    _run([sys.executable, "-m", "venv", "--without-pip", venv])
    site = Path(_run([venv / "bin" / "python", "-c",
                      "import sysconfig; print(sysconfig.get_paths()['purelib'])"]).stdout.strip())
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return venv, site


@pytest.mark.slow  # builds a wheel, makes a venv, computes the default atlas: about a minute
def test_the_wheel_installs_and_runs_atlas_in_a_fresh_venv(tmp_path):
    """``python -m build`` makes a wheel of pendulum-atlas (this version, the page's assets,
    the license); installed into a new venv (its dependencies from this venv's
    site-packages: nothing downloaded, the wheel itself --no-deps), ``atlas run`` of an
    empty config writes the default atlas from a folder outside the checkout, with atlas
    imported from the venv, not from the repository."""
    pytest.importorskip("build")
    source = _source_tree(tmp_path / "source")
    _run([sys.executable, "-m", "build", "--wheel", "--outdir", tmp_path / "dist", source],
         timeout=600)
    (wheel,) = (tmp_path / "dist").glob("*.whl")
    assert wheel.name.startswith(f"pendulum_atlas-{atlas.__version__}-py3-none-any")
    names = zipfile.ZipFile(wheel).namelist()
    assets = {n for n in names if n.startswith("atlas/views/view_assets/")}
    expected = {f"atlas/views/view_assets/{p.name}"
                for p in (REPO / "atlas" / "views" / "view_assets").iterdir() if p.is_file()}
    assert assets == expected and assets
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    metadata = zipfile.ZipFile(wheel).read(
        f"pendulum_atlas-{atlas.__version__}.dist-info/METADATA").decode()
    assert "Name: pendulum-atlas" in metadata and f"Version: {atlas.__version__}" in metadata

    venv, site = _venv_with_these_dependencies(tmp_path / "venv")
    _run([sys.executable, "-m", "pip", "--python", venv / "bin" / "python", "install",
          "--no-deps", "--no-index", "--quiet", wheel], timeout=300)

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "EMPTY.yaml").write_text("")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    where = _run([venv / "bin" / "python", "-c", "import atlas; print(atlas.__file__)"],
                 cwd=outside, env=env).stdout.strip()
    assert Path(where).is_relative_to(site)
    _run([venv / "bin" / "atlas", "run", "EMPTY.yaml", "-o", "out.h5", "--quiet"],
         cwd=outside, env=env, timeout=600)
    with atlas.open(outside / "out.h5") as tree:
        assert tree.attrs["atlas_version"] == atlas.__version__
        assert tree["attractor"].shape == (512, 512)  # the defaults: the essay's Figure 9
    # the page, from the installed assets
    _run([venv / "bin" / "atlas", "view", "out.h5"], cwd=outside, env=env, timeout=300)
    assert (outside / "out.html").stat().st_size > 0


@pytest.mark.slow  # an editable install into a new venv: about 15 s
def test_an_editable_install_wins_over_a_clone_folder_named_atlas(tmp_path):
    """A checkout cloned into a folder named ``atlas`` (its natural name) and installed with
    ``pip install -e`` (what ``make run`` does); a script run from the folder above sees that
    folder as a namespace package ``atlas`` on its path. The installed package must win, there
    as anywhere: ``import atlas`` is the checkout's ``atlas/__init__.py``, with ``atlas.label``."""
    parent = tmp_path / "projects"
    root = _source_tree(parent / "atlas")
    venv, _ = _venv_with_these_dependencies(tmp_path / "venv")
    _run([sys.executable, "-m", "pip", "--python", venv / "bin" / "python", "install",
          "--no-deps", "--quiet", "-e", root], timeout=300)
    (parent / "script.py").write_text("import atlas\nprint(atlas.__file__, atlas.label.__name__)\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    for command in (["script.py"], ["-c", "exec(open('script.py').read())"]):
        out = _run([venv / "bin" / "python", *command], cwd=parent, env=env).stdout.split()
        assert out == [str(root / "atlas" / "__init__.py"), "label"]
