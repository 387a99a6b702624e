#!/usr/bin/env bash
# Runs every bad-input case of tests/corpus/cases.txt through cloud-analysis or scene-render and
# checks the promise for bad input: the expected exit code, exactly one line on stderr (besides
# warnings) that starts with the tool's name and names the file or flag at fault, nothing left
# behind in the output folder (compared before and after, hidden temp files included, an
# earlier file unchanged), and time and peak memory under bounds.
#
# usage: run_corpus.sh --cloud-analysis EXE --scene-render EXE --samples DIR --work DIR
#                      [--sanitize] [-k SUBSTRING]
#   --sanitize: a looser time bound (ASan is slow), no memory bounds
#   -k: only the cases whose name contains SUBSTRING
set -uo pipefail

here=$(cd "$(dirname "$0")" && pwd)
ca="" sr="" samples="" work="" sanitize=0 only=""
while [ $# -gt 0 ]; do
    case $1 in
        --cloud-analysis) ca=$2; shift 2 ;;
        --scene-render) sr=$2; shift 2 ;;
        --samples) samples=$2; shift 2 ;;
        --work) work=$2; shift 2 ;;
        --sanitize) sanitize=1; shift ;;
        -k) only=$2; shift 2 ;;
        *) echo "run_corpus.sh: unknown option $1" >&2; exit 2 ;;
    esac
done
if [ -z "$ca" ] || [ -z "$sr" ] || [ -z "$samples" ] || [ -z "$work" ]; then
    sed -n '8,9p' "$0" >&2
    exit 2
fi

seconds=15 max_mib=1024 max_line=400  # an error line names a pointer or a path, not a dump
[ "$sanitize" = 0 ] || seconds=60
rm -rf "$work"
mkdir -p "$work"
gen=$work/gen out=$work/out
python3 "$here/make_hostile.py" "$gen" || exit 1

# Every entry under the output folder (hidden ones too) with its type and content hash.
snapshot() {
    (cd "$out" && find . -mindepth 1 -printf '%y %p\n' | sort &&
        find . -type f -print0 | sort -z | xargs -0 -r sha256sum)
}

# run_case NAME TOOL CODE NAMES DATA_MIB ARGS: prints the problems, one a line.
run_case() {
    local name=$1 tool=$2 code=$3 names=$4 data_mib=$5 args=$6 exe
    rm -rf "$out"
    mkdir -p "$out/dir"
    echo '{"earlier": "file"}' >"$out/keep.json"
    echo 'earlier image' >"$out/keep.png"
    echo -n x >"$out/dir/inside"
    snapshot >"$work/before"
    local syn=$samples/synthetic
    args=${args//\{stereo\}/--left $syn/left.png --right $syn/right.png}
    args=${args//\{calib\}/--calib $syn/calib.yaml}
    args=${args//\{scene\}/$syn/expected_entities.json}
    args=${args//\{c\}/$here/cases}
    args=${args//\{g\}/$gen}
    args=${args//\{s\}/$samples}
    args=${args//\{o\}/$out}
    case $tool in
        ca) tool=cloud-analysis exe=$ca ;;
        sr) tool=scene-render exe=$sr ;;
    esac
    local -a argv
    read -ra argv <<<"$args"
    local start=$EPOCHREALTIME rc
    (
        [ -z "$data_mib" ] || ulimit -d $((data_mib * 1024))
        exec timeout -s KILL "$seconds" /usr/bin/time -f %M -o "$work/rss" "$exe" "${argv[@]}"
    ) </dev/null >/dev/null 2>"$work/err"
    rc=$?
    local took
    took=$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
    if [ "$rc" = 137 ]; then
        echo "still running after $seconds s (killed)"
        return
    fi
    # GNU time notes a signal on the child's stderr; the rest is the tool's.
    grep -v "^Command \(terminated by\|exited with\)" "$work/err" >"$work/stderr"
    grep -v ": warning: " "$work/stderr" >"$work/errors"
    local lines first
    lines=$(wc -l <"$work/errors")
    first=$(head -1 "$work/errors")
    [ "$rc" = "$code" ] || echo "exit $rc, expected $code"
    if [ "$lines" != 1 ]; then
        echo "$lines error lines, expected 1"
    elif [[ $first != "$tool: "* || $first != *"$names"* ]]; then
        echo "error line does not start with '$tool: ' and name '$names'"
    elif [ ${#first} -gt $max_line ]; then
        echo "error line of ${#first} characters, more than $max_line"
    fi
    snapshot >"$work/after"
    cmp -s "$work/before" "$work/after" ||
        echo "output folder changed: $(diff "$work/before" "$work/after" | grep '^[<>]' | head -3 |
            tr '\n' ' ')"
    awk -v t="$took" -v s="$seconds" 'BEGIN { exit !(t > s) }' && echo "took $took s"
    local rss
    rss=$(tail -1 "$work/rss" 2>/dev/null)
    [ -n "$rss" ] && [ "$rss" -gt "$peak_kib" ] && peak_kib=$rss
    [ "$sanitize" = 1 ] || [ -z "$rss" ] || [ "$rss" -le $((max_mib * 1024)) ] ||
        echo "peak memory $((rss / 1024)) MiB, more than $max_mib MiB"
}

ran=0 failed=0 peak_kib=0
while IFS='|' read -r name tool code names data_mib args; do
    case $name in '#'* | '') continue ;; esac
    [[ $name == *"$only"* ]] || continue
    if [ "$sanitize" = 1 ] && [ -n "$data_mib" ]; then
        echo "skip $name (a data limit and the sanitizers' shadow memory do not mix)"
        continue
    fi
    ran=$((ran + 1))
    run_case "$name" "$tool" "$code" "$names" "$data_mib" "$args" >"$work/problems"
    if [ -s "$work/problems" ]; then
        failed=$((failed + 1))
        echo "FAIL $name"
        sed 's/^/       /' "$work/problems"
        echo "       stderr: $(head -5 "$work/err" | tr '\n' '|')"
    else
        echo "ok   $name"
    fi
done <"$here/cases.txt"
echo "$ran cases, $failed failed, largest peak memory of a run $((peak_kib / 1024)) MiB"
rm -rf "$work"
[ "$ran" -gt 0 ] && [ "$failed" = 0 ]
