#!/usr/bin/env bash
# Loads and renders a thumbnail of every stage of public USD test corpora, and reports each
# stage that fails with the renderer's one-line reason.
#
#   tools/usd_corpus.sh [--from NAME=DIR]... [--only NAME] [--bin PATH] [--out DIR]
#                       [--timeout SECONDS] [--resolution WxH] [--spp N] [--markdown FILE]
#
# Corpora (NAME, pinned commit, licence):
#   usd-wg   https://github.com/usd-wg/assets   274fa4584dd6afe7e7d84ea30e1ec9c652858d9a  Apache-2.0
#   luxtest  https://github.com/pmolodo/luxtest 9d555a66d0a699855342df5491a93851b3e011c2  CC BY 4.0
#
# Each corpus is downloaded once (the GitHub archive of the pinned commit) into
# ${XDG_CACHE_HOME:-~/.cache}/spectral-render/usd-corpus/NAME-COMMIT, or taken from an
# existing checkout with --from NAME=DIR. Every .usd, .usda, .usdc and .usdz file is rendered
# with `spectral-render STAGE --resolution 64x64 --spp 4` under `timeout` (default 60 s a
# stage), the EXR and a PNG thumbnail written under --out (default: the cache's out/NAME/).
# The summary is a markdown table on stdout (and in --markdown FILE): stage, loaded (yes, no,
# timeout), the error line, render seconds (load included). Exit status 0 when the run
# completed, whatever the stages did; 1 on a usage or download error.
set -euo pipefail

PROG=usd_corpus.sh
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
declare -A URL=(
    [usd-wg]=https://github.com/usd-wg/assets
    [luxtest]=https://github.com/pmolodo/luxtest
)
declare -A COMMIT=(
    [usd-wg]=274fa4584dd6afe7e7d84ea30e1ec9c652858d9a
    [luxtest]=9d555a66d0a699855342df5491a93851b3e011c2
)
NAMES=(usd-wg luxtest)
declare -A FROM=()
CACHE="${XDG_CACHE_HOME:-$HOME/.cache}/spectral-render/usd-corpus"
BIN="$ROOT/target/release/spectral-render"
OUT=""
TIMEOUT=60
RESOLUTION=64x64
SPP=4
MARKDOWN=""
ONLY=""

fail() {
    echo "$PROG: $*" >&2
    exit 1
}

while [ $# -gt 0 ]; do
    case "$1" in
        --from)
            [ $# -ge 2 ] && [[ "$2" == *=* ]] || fail "--from needs NAME=DIR"
            name="${2%%=*}"
            [ -n "${URL[$name]+x}" ] || fail "unknown corpus '$name' (known: ${NAMES[*]})"
            [ -d "${2#*=}" ] || fail "--from $2: not a directory"
            FROM[$name]="$(cd "${2#*=}" && pwd)"
            shift 2 ;;
        --only) ONLY="${2:?}"; [ -n "${URL[$ONLY]+x}" ] || fail "unknown corpus '$ONLY'"; shift 2 ;;
        --bin) BIN="${2:?}"; shift 2 ;;
        --out) OUT="${2:?}"; shift 2 ;;
        --timeout) TIMEOUT="${2:?}"; shift 2 ;;
        --resolution) RESOLUTION="${2:?}"; shift 2 ;;
        --spp) SPP="${2:?}"; shift 2 ;;
        --markdown) MARKDOWN="${2:?}"; shift 2 ;;
        -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) fail "unknown argument '$1' (see --help)" ;;
    esac
done
[ -x "$BIN" ] || fail "no renderer at $BIN (cargo build --release, or --bin PATH)"
[ -n "$OUT" ] || OUT="$CACHE/out"

# The corpus NAME's directory: --from, else the cached download of its pinned commit.
corpus_dir() {
    local name="$1" dir
    if [ -n "${FROM[$name]+x}" ]; then
        echo "${FROM[$name]}"
        return
    fi
    dir="$CACHE/$name-${COMMIT[$name]}"
    if [ ! -d "$dir" ]; then
        mkdir -p "$CACHE"
        local tmp="$dir.download"
        rm -rf "$tmp" && mkdir -p "$tmp"
        echo "downloading ${URL[$name]} at ${COMMIT[$name]}" >&2
        curl -fsSL "${URL[$name]}/archive/${COMMIT[$name]}.tar.gz" \
            | tar -xz -C "$tmp" --strip-components=1 \
            || fail "could not download ${URL[$name]} (use --from $name=DIR with a checkout)"
        mv "$tmp" "$dir"
    fi
    echo "$dir"
}

# One table cell: pipes escaped, on one line, at most 200 characters.
cell() {
    local s="${1//|/\\|}"
    s="${s//$'\n'/ }"
    [ ${#s} -le 200 ] || s="${s:0:197}..."
    printf '%s' "$s"
}

table=$(mktemp)
trap 'rm -f "$table"' EXIT
{
    echo "| stage | loaded | error | render s |"
    echo "|---|---|---|---|"
} >"$table"
total=0
loaded=0
for name in "${NAMES[@]}"; do
    [ -z "$ONLY" ] || [ "$ONLY" = "$name" ] || continue
    dir="$(corpus_dir "$name")"
    while IFS= read -r -d '' stage; do
        rel="${stage#"$dir"/}"
        out="$OUT/$name/${rel%.*}"
        mkdir -p "$(dirname "$out")"
        log="$out.log"
        start=$(date +%s.%N)
        status=0
        timeout --kill-after=5 "$TIMEOUT" "$BIN" "$stage" -o "$out.exr" --preview "$out.png" \
            --resolution "$RESOLUTION" --spp "$SPP" >"$log" 2>&1 || status=$?
        seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
        total=$((total + 1))
        case $status in
            0) state=yes; error=""; loaded=$((loaded + 1)) ;;
            124|137) state=timeout; error="no image after ${TIMEOUT} s" ;;
            *)
                state=no
                error="$(grep -m1 '^error:' "$log" || true)"
                [ -n "$error" ] || error="exit status $status: $(tail -n 1 "$log")" ;;
        esac
        error="${error#error: }"
        error="${error//"$dir"\//}"
        printf '| %s/%s | %s | %s | %.1f |\n' "$name" "$(cell "$rel")" "$state" \
            "$(cell "$error")" "$seconds" >>"$table"
    done < <(find "$dir" -type f \( -name '*.usd' -o -name '*.usda' -o -name '*.usdc' \
                -o -name '*.usdz' \) -not -path '*/.git/*' -print0 | sort -z)
done
echo "" >>"$table"
echo "$loaded of $total stages loaded and rendered ($(date -u +%Y-%m-%d), $("$BIN" --version))." >>"$table"
cat "$table"
[ -z "$MARKDOWN" ] || cp "$table" "$MARKDOWN"
