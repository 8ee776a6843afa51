#!/usr/bin/env bash
# Makes every picture of docs/gallery.md with the commands that page shows, and times them.
#
#   docs/gallery.sh          builds hirad in release, runs every command of the `sh` blocks of
#                            docs/gallery.md in order, copies the PNG pictures (--image) into
#                            docs/images/ and writes the wall time of each command, with the
#                            machine's core count and load average, to docs/gallery-times.md
#   docs/gallery.sh --quick  only the commands not marked `<!-- slow: ... -->` (the small
#                            scenes); pictures and times stay in the scratch folder, docs/ is
#                            not touched: a check of the script
#
# The commands run in a scratch folder that has a link `fixtures` to the repository's, as in
# the docs test (std-runner/tests/docs_examples.rs): $GALLERY_WORK, by default gallery/ (or
# gallery-quick/) in the cargo target folder. It is emptied first, if it is one this script
# made. Logs of each command: logs/ in it.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
quick=0
case "${1:-}" in
"") ;;
--quick) quick=1 ;;
-h | --help)
    sed -n '2,15p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    exit 0
    ;;
*)
    echo "usage: docs/gallery.sh [--quick]" >&2
    exit 2
    ;;
esac

target=${CARGO_TARGET_DIR:-$repo/target}
case $target in
/*) ;;
*) target=$repo/$target ;;
esac
if [ $quick = 1 ]; then
    work=${GALLERY_WORK:-$target/gallery-quick}
else
    work=${GALLERY_WORK:-$target/gallery}
fi

# The commands of gallery.md's sh blocks, one a line: "slow|quick<TAB>WARNS<TAB>command". As in
# the docs test, a `<!-- slow: REASON -->` comment on the lines just before a fence marks its
# block slow, and each `<!-- warns: TEXT -->` there names a warning the block's commands may
# print (WARNS: those texts joined by \x1f, or - for none); any other warning fails the run.
commands=$(awk '
    function reset() { slow = 0; warns = "" }
    inblock && /^[[:space:]]*```[[:space:]]*$/ { inblock = 0; reset(); next }
    inblock {
        if (!run) next
        line = $0
        sub(/^[[:space:]]+/, "", line)
        if (line == "" || line ~ /^#/) next
        if (line ~ /\\$/) { print "gallery.md:" NR ": a continued line: write each command on one line" > "/dev/stderr"; exit 1 }
        print (blockslow ? "slow" : "quick") "\t" (blockwarns == "" ? "-" : blockwarns) "\t" line
        next
    }
    /^[[:space:]]*<!--.*-->[[:space:]]*$/ {
        if ($0 ~ /<!--[[:space:]]*slow:/) slow = 1
        if ($0 ~ /<!--[[:space:]]*warns:/) {
            text = $0
            sub(/^[[:space:]]*<!--[[:space:]]*warns:[[:space:]]*/, "", text)
            sub(/[[:space:]]*-->[[:space:]]*$/, "", text)
            warns = (warns == "" ? text : warns "\037" text)
        }
        next
    }
    /^[[:space:]]*```/ {
        info = $0
        sub(/^[[:space:]]*```/, "", info)
        split(info, w, " ")
        if (w[1] == "console") { print "gallery.md:" NR ": console blocks are not supported here" > "/dev/stderr"; exit 1 }
        run = (w[1] == "sh" || w[1] == "bash")
        blockslow = slow
        blockwarns = warns
        inblock = 1
        next
    }
    { reset() }
' "$repo/docs/gallery.md")
if [ -z "$commands" ]; then
    echo "docs/gallery.md: no commands found" >&2
    exit 1
fi

echo "building hirad (release)" >&2
(cd "$repo" && cargo build --release -p hirad)
bin=$target/release/hirad
if [ ! -x "$bin" ]; then
    echo "no $bin after the build (CARGO_TARGET_DIR?)" >&2
    exit 1
fi

if [ -e "$work" ]; then
    if [ -e "$work/.hirad-gallery" ]; then
        rm -rf "$work"
    else
        echo "$work exists and is not a folder this script made: give another GALLERY_WORK" >&2
        exit 1
    fi
fi
mkdir -p "$work/logs"
touch "$work/.hirad-gallery"
ln -s "$repo/fixtures" "$work/fixtures"

commit=$(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo unknown)
if ! git -C "$repo" diff --quiet HEAD 2>/dev/null; then
    commit="$commit with uncommitted changes"
fi
cores=$(nproc)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
started=$(date -u '+%Y-%m-%d %H:%M UTC')

if [ $quick = 1 ]; then
    times=$work/gallery-times.md
    mode="\`docs/gallery.sh --quick\` (the quick commands only)"
else
    times=$repo/docs/gallery-times.md
    mode="\`docs/gallery.sh\`"
fi

# Writes the table of the commands run so far; $1 says whether the run is complete. Written
# after every command, so that a run stopped halfway leaves what it measured, marked as such.
write_times() {
    local state=$1 load_now
    load_now=$(cut -d' ' -f1-3 /proc/loadavg)
    {
        echo "# Gallery times"
        echo
        echo "Written by $mode, started $started: hirad at commit $commit, release build;"
        echo "$cores cores (\`nproc\`), load average $load_before before the run and $load_now at its"
        echo "last line (1, 5 and 15 minutes). Wall time of each command of [gallery.md](gallery.md),"
        echo "measured by the script; the load column is the 1-minute load average when the command"
        echo "started (other work on the machine slows it)."
        echo
        if [ "$state" != complete ]; then
            echo "**Incomplete**: $state."
            echo
        fi
        echo "| command | wall time (s) | load |"
        echo "| --- | ---: | ---: |"
        if [ ${#rows[@]} -gt 0 ]; then
            printf '%s\n' "${rows[@]}"
        fi
    } >"$times.tmp"
    mv "$times.tmp" "$times"
}

rows=()
pictures=()
n=0
while IFS=$'\t' read -r kind warns cmd; do
    read -r -a words <<<"$cmd"
    case ${words[0]} in
    hirad) ;;
    docs/gallery.sh) continue ;; # this script, as the page shows how to run it
    *)
        echo "docs/gallery.md: no rule to run '$cmd' (only hirad commands)" >&2
        exit 1
        ;;
    esac
    if [ "$kind" = slow ] && [ $quick = 1 ]; then
        echo "skipped (slow): $cmd" >&2
        continue
    fi
    n=$((n + 1))
    log=$work/logs/$n.txt
    load=$(cut -d' ' -f1 /proc/loadavg)
    echo "running: $cmd" >&2
    start=$(date +%s.%N)
    write_times "the run is at \`$cmd\` (command $n) or was stopped there"
    if ! (cd "$work" && "$bin" "${words[@]:1}") >"$log" 2>&1; then
        echo "failed: $cmd (log $log):" >&2
        tail -n 20 "$log" >&2
        write_times "\`$cmd\` failed"
        exit 1
    fi
    end=$(date +%s.%N)
    seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
    # A warning the page does not name fails the run, as in the docs test.
    unnamed=$({ grep -i warning "$log" || true; } | while IFS= read -r line; do
        named=0
        if [ "$warns" != - ]; then
            IFS=$'\037' read -r -a texts <<<"$warns"
            for t in "${texts[@]}"; do
                case $line in *"$t"*) named=1 ;; esac
            done
        fi
        if [ $named = 0 ]; then echo "$line"; fi
    done)
    if [ -n "$unnamed" ]; then
        echo "warned: $cmd (log $log):" >&2
        echo "$unnamed" >&2
        write_times "\`$cmd\` warned: $unnamed"
        exit 1
    fi
    grep -i warning "$log" >&2 || true
    echo "  $seconds s" >&2
    rows+=("| \`$cmd\` | $seconds | $load |")
    for ((i = 1; i < ${#words[@]}; i++)); do
        if [ "${words[i]}" = --image ] && [ $((i + 1)) -lt ${#words[@]} ]; then
            pictures+=("${words[i + 1]}")
        fi
    done
done <<<"$commands"

write_times complete

for p in "${pictures[@]}"; do
    if [ ! -s "$work/$p" ]; then
        echo "$p was not written" >&2
        exit 1
    fi
done
if [ $quick = 0 ]; then
    # Every picture the page shows must have been made now.
    for shown in $(grep -o 'images/[A-Za-z0-9_.-]*\.png' "$repo/docs/gallery.md" | sort -u); do
        name=${shown#images/}
        if [ ! -s "$work/$name" ]; then
            echo "docs/gallery.md shows $shown but no command made $name" >&2
            exit 1
        fi
    done
    # The PNGs (the page shows them); EXR pictures are references for --reference-image.
    for p in "${pictures[@]}"; do
        case $p in
        *.png) cp "$work/$p" "$repo/docs/images/$p" ;;
        esac
    done
    echo "pictures copied into docs/images/; times in $times" >&2
else
    echo "pictures and times in $work (docs/ untouched)" >&2
fi
