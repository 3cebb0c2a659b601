#!/usr/bin/env bash
# Creates <repo>/.venv (Python 3.11) with the pinned packages of tools/requirements.txt.
#
# Idempotent and quiet: prints nothing when the venv is already up to date. The venv is rebuilt
# from scratch only when tools/requirements.txt changes (its sha256 is stamped inside the venv).
# Safe to run concurrently (serialised with flock on tools/requirements.txt). Works from any cwd.
# Exits non-zero with a one-line message on failure. Override the interpreter with $PYTHON.
set -u -o pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)" || { echo "venv.sh: cannot resolve script directory" >&2; exit 1; }
repo="$(dirname "$here")"
req="$here/requirements.txt"
venv="$repo/.venv"
stamp="$venv/.requirements.sha256"

fail() { echo "venv.sh: $*" >&2; exit 1; }

[ -r "$req" ] || fail "missing $req"
command -v flock >/dev/null 2>&1 || fail "flock not found (util-linux)"
want="$(sha256sum "$req" | cut -d' ' -f1)" || fail "cannot hash $req"

up_to_date() { [ -x "$venv/bin/python" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; }

# Fast path without the lock.
up_to_date && exit 0

exec 9<"$req" || fail "cannot open $req for locking"
flock 9 || fail "cannot lock $req"
# Another process may have finished the install while we waited.
up_to_date && exit 0

py="${PYTHON:-}"
if [ -z "$py" ]; then
    if command -v python3.11 >/dev/null 2>&1; then py=python3.11; else py=python3; fi
fi
command -v "$py" >/dev/null 2>&1 || fail "no Python interpreter ($py) found"
"$py" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null || fail "$py is older than Python 3.11"

echo "venv.sh: installing tools/requirements.txt into $venv ..." >&2
rm -rf "$venv"
log="$(mktemp "${TMPDIR:-/tmp}/venv-install.XXXXXX.log")" || fail "cannot create a temporary log"
if ! { "$py" -m venv "$venv" && "$venv/bin/python" -m pip install --disable-pip-version-check -q -r "$req"; } >"$log" 2>&1; then
    rm -rf "$venv"
    fail "installing $req failed (log: $log)"
fi
rm -f "$log"
echo "$want" >"$stamp" || fail "cannot write $stamp"
