"""`clear --version`: the version, and from a checkout the commit (+dirty), read from .git's
files without a `git` process (clearcli/provenance.py `version_line`)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import REPO, run_clear

from clearcli import __version__, provenance

GIT = shutil.which("git")
needs_git = pytest.mark.skipif(GIT is None, reason="git is not installed")


def git(repo: Path, *args: str) -> str:
    env = {
        **os.environ,
        "GIT_AUTHOR_NAME": "t",
        "GIT_AUTHOR_EMAIL": "t@t",
        "GIT_COMMITTER_NAME": "t",
        "GIT_COMMITTER_EMAIL": "t@t",
    }
    out = subprocess.run(["git", *args], cwd=repo, env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def git_says_dirty(repo: Path) -> bool:
    return git(repo, "describe", "--always", "--dirty").endswith("-dirty")


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    root = tmp_path / "checkout"
    (root / "pkg" / "sub").mkdir(parents=True)
    git(root, "init", "-q")
    for k in range(30):
        (root / "pkg" / f"m{k}.py").write_text(f"x = {k}\n")
    (root / "pkg" / "sub" / "deep.txt").write_text("deep\n")
    os.symlink("m0.py", root / "pkg" / "link.py")
    git(root, "add", ".")
    git(root, "commit", "-q", "-m", "one")
    # the index written after the files: no entry is "racily clean"
    time.sleep(0.01)
    git(root, "update-index", "--refresh")
    return root


@needs_git
@pytest.mark.parametrize("index_version", ["2", "3", "4"])
def test_the_dirty_check_agrees_with_git(repo: Path, index_version: str) -> None:
    git(repo, "update-index", f"--index-version={index_version}")
    found = provenance._git_dir(repo / "pkg" / "sub")
    assert found == (repo, repo / ".git")
    assert provenance._git_commit(repo / "pkg") == git(repo, "rev-parse", "HEAD")

    def both() -> tuple[bool, bool]:
        return provenance._git_dirty(repo, repo / ".git"), git_says_dirty(repo)

    assert both() == (False, False)
    (repo / "untracked.txt").write_text("not tracked\n")  # git ignores these: so do we
    assert both() == (False, False)
    target = repo / "pkg" / "m7.py"
    target.write_text("x = 8\n")  # same size, new content
    assert both() == (True, True)
    target.write_text("x = 7\n")  # back as committed, a newer time: hashed, clean
    assert both() == (False, False)
    (repo / "pkg" / "sub" / "deep.txt").unlink()
    assert both() == (True, True)
    git(repo, "checkout", "--", "pkg/sub/deep.txt")
    (repo / "pkg" / "m29.py").write_text("x = 29  # longer\n")
    assert both() == (True, True)


@needs_git
def test_a_linked_worktree_reads_its_own_head_and_index(repo: Path, tmp_path: Path) -> None:
    linked = tmp_path / "linked"
    git(repo, "worktree", "add", "-q", "-b", "side", str(linked))
    (linked / "pkg" / "m1.py").write_text("x = 100\n")
    git(linked, "commit", "-q", "-am", "two")
    found = provenance._git_dir(linked / "pkg")
    assert found is not None
    root, gitdir = found
    assert root == linked and gitdir.is_dir() and gitdir != repo / ".git"
    assert provenance._git_commit(linked) == git(linked, "rev-parse", "HEAD") != git(repo, "rev-parse", "HEAD")
    assert provenance._git_dirty(root, gitdir) is False
    (linked / "pkg" / "m2.py").write_text("x = 200\n")
    assert provenance._git_dirty(root, gitdir) is True
    assert provenance._git_dirty(repo, repo / ".git") is False  # the main tree is untouched


@needs_git
def test_an_unreadable_index_or_a_spent_budget_says_dirty(repo: Path) -> None:
    (repo / "pkg" / "m3.py").touch()  # a newer time: the check hashes it
    assert provenance._git_dirty(repo, repo / ".git", budget_s=0.0) is True
    (repo / ".git" / "index").write_bytes(b"not an index")
    assert provenance._git_dirty(repo, repo / ".git") is True


def test_outside_a_checkout_there_is_no_commit(tmp_path: Path) -> None:
    if any((p / ".git").exists() for p in (tmp_path, *tmp_path.parents)):
        pytest.skip("the temporary folder is itself inside a checkout")
    assert provenance._git_dir(tmp_path) is None
    assert provenance._git_commit(tmp_path) is None
    (tmp_path / ".git").write_text("not a gitdir line\n")  # a stray .git file: no checkout
    assert provenance._git_dir(tmp_path) is None


def test_a_wheel_outside_a_checkout_says_the_version_alone(tmp_path: Path) -> None:
    """The package copied where no .git is above it (as a wheel installs it): the line
    names the version and no commit."""
    copy = tmp_path / "site" / "clearcli"
    shutil.copytree(REPO / "clearcli", copy, ignore=shutil.ignore_patterns("__pycache__"))
    code = "from clearcli import provenance; print(provenance.version_line())"
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "site")}
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stderr
    if any((p / ".git").exists() for p in tmp_path.parents):
        pytest.skip("the temporary folder is itself inside a checkout")
    assert out.stdout.strip() == f"clear {__version__}"


@needs_git
def test_the_line_names_this_checkouts_commit() -> None:
    line = provenance.version_line()
    head = git(REPO, "rev-parse", "HEAD")
    dirty = "+dirty" if git_says_dirty(REPO) else ""
    assert line == f"clear {__version__} (commit {head[:7]}{dirty})"


def test_the_line_is_cheap() -> None:
    provenance.version_line()  # warm the file cache
    t0 = time.perf_counter()
    provenance.version_line()
    assert time.perf_counter() - t0 < 0.5


def test_clear_version_names_the_commit() -> None:
    done = run_clear("--version", timeout=60)
    assert done.returncode == 0
    assert re.fullmatch(rf"clear {re.escape(__version__)} \(commit [0-9a-f]{{7}}(\+dirty)?\)\n", done.stdout)
