"""partisim.progress: the display is chosen as documented (off, tqdm, plain stderr line)."""

import sys
import types

from partisim import progress


def test_disabled_display_writes_nothing(capsys):
    with progress.make_progress(5, enabled=False, desc="frames") as bar:
        bar.update(5)
    assert capsys.readouterr().err == ""


def test_plain_line_without_tqdm(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # import fails as if not installed
    bar = progress.make_progress(3, enabled=True, desc="frames")
    for _ in range(3):
        bar.update(1)
    bar.close()
    bar.close()  # a second close writes nothing more
    err = capsys.readouterr().err
    assert err.endswith("\n") and err.count("\n") == 1
    assert "frames: 3/3" in err.rsplit("\r", 1)[-1]


def test_tqdm_used_when_installed(monkeypatch):
    made = {}

    class FakeTqdm:
        def __init__(self, total, desc, file):
            made.update(total=total, desc=desc, n=0, closed=False)

        def update(self, n):
            made["n"] += n

        def close(self):
            made["closed"] = True

    monkeypatch.setitem(sys.modules, "tqdm.auto", types.SimpleNamespace(tqdm=FakeTqdm))
    with progress.make_progress(4, enabled=True, desc="frames") as bar:
        bar.update(2)
        bar.update(2)
    assert made == {"total": 4, "desc": "frames", "n": 4, "closed": True}


def test_default_follows_terminal_and_jupyter(monkeypatch):
    class Stream:
        def __init__(self, tty):
            self.tty = tty

        def isatty(self):
            return self.tty

        def write(self, s):
            pass

        def flush(self):
            pass

    monkeypatch.delitem(sys.modules, "IPython", raising=False)
    monkeypatch.setattr(sys, "stderr", Stream(False))
    assert progress.progress_wanted(None) is False
    monkeypatch.setattr(sys, "stderr", Stream(True))
    assert progress.progress_wanted(None) is True
    assert progress.progress_wanted(False) is False

    # A Jupyter kernel: stderr is no terminal, but IPython's shell runs under IPKernelApp.
    monkeypatch.setattr(sys, "stderr", Stream(False))
    shell = types.SimpleNamespace(config={"IPKernelApp": {}})
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))
    assert progress.in_jupyter() is True
    assert progress.progress_wanted(None) is True
    # Plain IPython on a terminal is not a kernel.
    plain = types.SimpleNamespace(config={})
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: plain))
    assert progress.in_jupyter() is False
