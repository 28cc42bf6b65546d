"""The README's Python example runs as written (from the repository root, as a newcomer
would run it after `pip install ./python`)."""

import re

from conftest import REPO


def test_the_readme_python_example_runs(monkeypatch, capsys):
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("### Python", 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, "README.md's Python section has no python block"
    monkeypatch.chdir(REPO)
    scope: dict = {}
    exec(compile(match.group(1), "README.md (Python section)", "exec"), scope)
    # What the example promises: CSR lists of every particle, a scene run, a population.
    assert len(scope["offsets"]) == 100_001 and scope["offsets"][-1] == len(scope["indices"])
    assert scope["sim"].time > 0.0
