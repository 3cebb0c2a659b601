#!/usr/bin/env python3
"""Flatten a USD stage into one self-contained .usda layer.

    python tools/flatten.py in.usd[a|c|z] out.usda

Opens the stage with usd-core (`pip install -r tools/requirements.txt`), composes it
(sublayers, references, payloads, inherits, variant selections), and exports the result as a
single text layer that spectral-render reads without any composition. Asset paths (textures)
are anchored by USD so that they still resolve from the output's location.

On failure prints one line, `flatten.py: <file>: <reason>`, to stderr and exits with status 1.
USD's own diagnostics are captured and folded into that line instead of being printed.
"""

import contextlib
import os
import re
import sys
import tempfile

PROG = "flatten.py"


def fail(subject, reason):
    """Prints a one-line error about `subject` and exits with status 1."""
    reason = " ".join(tf_commentary(str(reason)).split()) or "unknown error"
    print(f"{PROG}: {subject}: {reason}", file=sys.stderr)
    sys.exit(1)


def tf_commentary(text):
    """The messages of Tf errors ("Error in 'f' at line N in file F : 'message'"), without the
    C++ function and source locations; other text is returned unchanged."""
    messages = re.findall(r"Error in '[^']*' at line \d+ in file [^:]* : '(.*?)'\s*(?=Error in '|$)", text, re.S)
    return "; ".join(m.strip() for m in messages) if messages else text


@contextlib.contextmanager
def captured_stderr():
    """Redirects file descriptor 2 (where USD's C++ diagnostics go) into a buffer.

    Yields a list that holds the captured text once the block exits.
    """
    sys.stderr.flush()
    saved = os.dup(2)
    captured = []
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield captured
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            captured.append(sink.read().decode("utf-8", "replace"))


def first_diagnostic(text):
    """The most useful line of USD's captured diagnostic output, or ''."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    for line in lines:
        if "error" in line.lower() or "could not" in line.lower() or "failed" in line.lower():
            return line
    return lines[0] if lines else ""


def load_usd():
    """Imports usd-core's Usd and Tf modules, or fails with an install hint."""
    try:
        from pxr import Tf, Usd  # pylint: disable=import-outside-toplevel
    except ImportError:
        fail("pxr", "usd-core is not installed (pip install -r tools/requirements.txt)")
    return Usd, Tf


def open_stage(Usd, Tf, source):
    """Opens `source` with every payload loaded; fails on any composition error."""
    with captured_stderr() as log:
        try:
            stage = Usd.Stage.Open(source, Usd.Stage.LoadAll)
        except Tf.ErrorException as e:
            stage, error = None, e
        else:
            error = None
    if stage is None:
        fail(source, error or first_diagnostic(log[0]) or "cannot open the stage")
    errors = stage.GetCompositionErrors() if hasattr(stage, "GetCompositionErrors") else []
    if errors:
        fail(source, f"composition error: {errors[0]}")
    return stage


def export_flattened(Tf, stage, source, target):
    """Flattens `stage` and writes it to `target` as text."""
    with captured_stderr() as log:
        try:
            ok = stage.Flatten().Export(target)
        except Tf.ErrorException as e:
            ok, error = False, e
        else:
            error = None
    if not ok:
        fail(target, error or first_diagnostic(log[0]) or f"cannot write (flattening {source})")


def main(argv):
    if len(argv) != 3:
        fail("usage", f"python tools/{PROG} in.usd[a|c|z] out.usda")
    source, target = argv[1], argv[2]
    if not os.path.isfile(source):
        fail(source, "no such file")
    if not target.endswith(".usda"):
        fail(target, "the output must be a .usda file")
    Usd, Tf = load_usd()
    stage = open_stage(Usd, Tf, source)
    export_flattened(Tf, stage, source, target)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
