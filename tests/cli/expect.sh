#!/usr/bin/env bash
# Runs one command line of a tool and checks what the CLI promises: its exit code, stderr and
# stdout against extended regular expressions (`\n` is a newline, `.` matches one too), exactly
# one "<tool>: error: <where>: <reason>" line on stderr besides warnings when it exits 1 or 2,
# and the files it leaves behind.
#
# usage: expect.sh --code N [--stderr RE] [--stdout RE]
#                  [--output FILE [--exists 0|1] [--magic HEX]]
#                  [--folder DIR [--files "a|b|c"]] -- TOOL ARGS...
#   --output: FILE is removed first; afterwards it exists (--exists 1, starting with the bytes
#             --magic, a PNG's by default) or not (--exists 0); no hidden temporary file of the
#             atomic writers is left beside it.
#   --folder: DIR is removed first; afterwards it holds exactly the files --files names (PNGs
#             among them start with a PNG's bytes), or nothing at all.
# exit 0 when every check holds, 1 with the reason otherwise.
set -uo pipefail

png=89504e470d0a1a0a
code="" stderr_re="" stdout_re="" output="" exists=1 magic=$png folder="" files=""
while [ $# -gt 0 ]; do
    case $1 in
        --code) code=$2; shift 2 ;;
        --stderr) stderr_re=$2; shift 2 ;;
        --stdout) stdout_re=$2; shift 2 ;;
        --output) output=$2; shift 2 ;;
        --exists) exists=$2; shift 2 ;;
        --magic) magic=$2; shift 2 ;;
        --folder) folder=$2; shift 2 ;;
        --files) files=$2; shift 2 ;;
        --) shift; break ;;
        *) echo "expect.sh: unknown option $1" >&2; exit 2 ;;
    esac
done
if [ -z "$code" ] || [ $# -eq 0 ]; then
    echo "expect.sh: need --code and a command after --" >&2
    exit 2
fi

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
# The first bytes of a file as lower-case hex.
head_hex() { od -An -v -tx1 -N"$2" "$1" | tr -d ' \n'; }
matches() {
    local text=$1 re=${2//\\n/$'\n'}
    [[ $text =~ $re ]]
}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
[ -z "$output" ] || { mkdir -p "$(dirname "$output")" && rm -f "$output"; }
[ -z "$folder" ] || rm -rf "$folder"

"$@" </dev/null >"$work/out" 2>"$work/err"
rc=$?
err=$(cat "$work/err")$'\n'
out=$(tr -d '\0' <"$work/out")
[ -s "$work/err" ] || err=""
printf '%s' "$err" >&2

[ "$rc" = "$code" ] || fail "exit code $rc, expected $code"
[ -z "$stderr_re" ] || matches "$err" "$stderr_re" || fail "stderr does not match '$stderr_re'"
[ -z "$stdout_re" ] || matches "$out" "$stdout_re" || fail "stdout does not match '$stdout_re'"
if [ "$rc" = 1 ] || [ "$rc" = 2 ]; then
    tool=$(basename "$1")
    grep -v "^$tool: warning: " "$work/err" >"$work/errors"
    lines=$(wc -l <"$work/errors")
    [ "$lines" = 1 ] && matches "$(cat "$work/errors")" "^$tool: error: [^\n]+: " ||
        fail "expected one '$tool: error: <where>: <reason>' line besides warnings, got $lines"
fi

if [ -n "$output" ]; then
    if [ "$exists" = 1 ]; then
        [ -f "$output" ] || fail "no output file $output"
        got=$(head_hex "$output" $((${#magic} / 2)))
        [ "$got" = "$magic" ] || fail "$output starts with $got, expected $magic"
    elif [ -e "$output" ]; then
        fail "output $output left behind by a failed run"
    fi
    temps=$(find "$(dirname "$output")" -maxdepth 1 -name '.*.tmp-*' | head -3)
    [ -z "$temps" ] || fail "temporary files left behind: $temps"
fi

if [ -n "$folder" ]; then
    written=$( [ -d "$folder" ] && cd "$folder" && find . -type f | sed 's|^\./||' | sort)
    wanted=$(tr '|' '\n' <<<"$files" | sed '/^$/d' | sort)
    [ "$written" = "$wanted" ] ||
        fail "$folder holds [$(echo $written)], expected [$(echo $wanted)]"
    while read -r f; do
        case $f in
            *.png) [ "$(head_hex "$folder/$f" 8)" = $png ] || fail "$folder/$f is not a PNG" ;;
        esac
    done <<<"$wanted"
fi
exit 0
