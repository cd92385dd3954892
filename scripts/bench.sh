#!/usr/bin/env bash
# Rebuilds mrcheck and regenerates every bench table committed under
# docs/bench/ (ao, ghost, tracking, scene, multiview, map), each stamped with
# the commit it was made at and the exact command.
#
#   scripts/bench.sh [ao|ghost|tracking|scene|scene-unique|scene-instanced|multiview|map|measure|shadows|load ...]
#   (default: ao ghost tracking scene multiview map)
#
# Commit first, then run: the stamp names HEAD and says "dirty" when the
# working tree differs from it (tables of uncommitted code). Sizes are
# chosen so that all four finish in about 10 minutes on the shared 2-core
# build VM with Mesa llvmpipe (measured times in docs/bench/README.md);
# set MR_BENCH_FULL=1 for the benches' own, larger defaults. Benches are
# measurements: this script fails only when a bench cannot run.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
benches=("$@")
[ ${#benches[@]} -gt 0 ] || benches=(ao ghost tracking scene multiview map)
full=${MR_BENCH_FULL:-0}

cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target mrcheck >/dev/null
mr=./build/mrcheck

commit=$(git rev-parse --short HEAD)
dirty=clean
if [ -n "$(git status --porcelain -- . ':!docs/bench')" ]; then dirty=dirty; fi
when=$(date -u +%Y-%m-%dT%H:%MZ)

# stamp FILE COMMAND: one "# " line at the top of a CSV, a paragraph at the
# top of a Markdown file.
stamp() {
    local f=$1 cmd=$2 tmp
    tmp=$(mktemp)
    case $f in
    *.csv) printf '# made at commit %s (%s), %s, by: %s\n' "$commit" "$dirty" "$when" "$cmd" >"$tmp" ;;
    *.md) printf '_Made at commit `%s` (%s), %s, by `scripts/bench.sh`:_ `%s`\n\n' "$commit" "$dirty" "$when" "$cmd" >"$tmp" ;;
    esac
    cat "$f" >>"$tmp"
    mv "$tmp" "$f"
}

# csv_md CSV TITLE > MD: the CSV as a Markdown table ("#" lines become
# notes above it).
csv_md() {
    awk -F, -v title="$2" '
        BEGIN { print "## " title "\n" }
        /^#/ { sub(/^# ?/, ""); print "> " $0 "\n"; next }
        !hdr { hdr = 1; line = "|"; sep = "|"; for (i = 1; i <= NF; i++) { line = line " " $i " |"; sep = sep "---|" }
               print line; print sep; next }
        { line = "|"; for (i = 1; i <= NF; i++) { gsub(/"/, "", $i); line = line " " $i " |" } print line }
        END { print "" }' "$1"
}

# run NAME DIR CMD...: runs one bench into DIR (emptied first), keeps its
# stdout as NAME.log, stamps every CSV and Markdown file it wrote.
run() {
    local name=$1 dir=$2
    shift 2
    local cmd="$*"
    rm -rf "$dir"
    mkdir -p "$dir"
    echo "bench.sh: $cmd" >&2
    local t0=$SECONDS
    "$@" >"$dir/$name.log"
    echo "bench.sh: $name done in $((SECONDS - t0)) s" >&2
    for f in "$dir"/*.csv; do
        [ -e "$f" ] || continue
        csv_md "$f" "$(basename "$f")" >"${f%.csv}.table.md"
        stamp "${f%.csv}.table.md" "$cmd"
        stamp "$f" "$cmd"
    done
    for f in "$dir"/*.md; do
        case $f in *.table.md) ;; *) stamp "$f" "$cmd" ;; esac
    done
    sed -i "1i bench.sh: commit $commit ($dirty), $when: $cmd" "$dir/$name.log"
}

for b in "${benches[@]}"; do
    case $b in
    ao)
        if [ "$full" = 1 ]; then run bench_ao docs/bench/ao $mr bench ao --out docs/bench/ao --quiet
        else run bench_ao docs/bench/ao $mr bench ao --quick --frames 3 --out docs/bench/ao --quiet; fi ;;
    ghost)
        if [ "$full" = 1 ]; then run bench_ghost docs/bench/ghost $mr bench ghost --out docs/bench/ghost --quiet
        else run bench_ghost docs/bench/ghost $mr bench ghost --frames 3 --out docs/bench/ghost --quiet; fi ;;
    tracking)
        run bench_tracking docs/bench/tracking/640x480 \
            $mr bench tracking --recording recordings/demo --out docs/bench/tracking/640x480
        # The 1920x1080 recording (a tablet camera's size) is synthesised
        # (deterministic), not shipped: 36 frames spread over the path, no
        # motion blur, so a loaded 2-core machine renders it in minutes.
        tmp=$(mktemp -d)
        $mr synth --out "$tmp/rec1080" --size 1920x1080 --frames 36 --motion-blur 1 >/dev/null
        run bench_tracking docs/bench/tracking/1920x1080 \
            $mr bench tracking --recording "$tmp/rec1080" --out docs/bench/tracking/1920x1080
        rm -rf "$tmp" ;;
    scene)
        # The bench writes its generated scenes next to the CSV: keep only
        # the tables.
        if [ "$full" = 1 ]; then run bench_scene docs/bench/scene $mr bench scene --out docs/bench/scene --quiet
        else run bench_scene docs/bench/scene $mr bench scene --sizes 1M,5M --frames 3 --out docs/bench/scene --quiet; fi
        find docs/bench/scene -type f ! -name '*.csv' ! -name '*.md' ! -name '*.svg' ! -name '*.log' -delete
        find docs/bench/scene -mindepth 1 -type d -empty -delete ;;
    shadows)
        # Not in the default list: about 30 minutes here (13 cases x 2 views).
        run bench_shadows docs/bench/shadows $mr bench shadows --out docs/bench/shadows --quiet ;;
    multiview)
        run bench_multiview docs/bench/multiview $mr bench multiview --out docs/bench/multiview --quiet
        # issue 14: the shared work (about 10 minutes here, mostly the
        # synthetic factory's 48 views drawn per-view and shared).
        run bench_multiview_shared docs/bench/multiview/shared \
            $mr bench multiview --shared-only --out docs/bench/multiview/shared --quiet ;;
    map)
        # CPU only, about 10 s: the full photo counts 10..200, 5 seeds.
        run bench_map docs/bench/map $mr bench map --out docs/bench/map ;;
    scene-unique)
        # Unique CAD-like geometry (issue 17); its LOD build (certified
        # bounds) dominates: small sizes unless full. Full: 320x240 and one
        # timed frame of the full-detail cases (seconds each at 20M), so
        # that it fits in about half an hour here (lane bench).
        if [ "$full" = 1 ]; then run bench_scene_unique docs/bench/scene_unique $mr bench scene --unique --sizes 2M,10M,20M --frames 3 --full-detail-frames 1 --size 320x240 --out docs/bench/scene_unique --quiet
        else run bench_scene_unique docs/bench/scene_unique $mr bench scene --unique --sizes 100k,200k --frames 3 --out docs/bench/scene_unique --quiet; fi
        find docs/bench/scene_unique -type f ! -name '*.csv' ! -name '*.md' ! -name '*.svg' ! -name '*.log' -delete
        find docs/bench/scene_unique -mindepth 1 -type d -empty -delete ;;
    scene-instanced)
        # issue 17: the instanced factory at scene-unique's full sizes and
        # image size, for the two tables side by side; about 10 minutes
        # here, not in the default list.
        run bench_scene_instanced docs/bench/scene_instanced $mr bench scene --sizes 2M,10M,20M --frames 3 --full-detail-frames 1 --size 320x240 --out docs/bench/scene_instanced --quiet
        find docs/bench/scene_instanced -type f ! -name '*.csv' ! -name '*.md' ! -name '*.svg' ! -name '*.log' -delete
        find docs/bench/scene_instanced -mindepth 1 -type d -empty -delete ;;
    measure)
        # CPU only, about 2 minutes here: synthetic halls, projected
        # corners with noise (no rendering), 2 map seeds x 20 points x 5
        # deviations per row; not in the default list.
        run bench_measure docs/bench/measure $mr bench measure --out docs/bench/measure ;;
    load)
        # issue 17 (lane gltf): first loads of the factories and their
        # gltfpack files, CPU only, about 60 s; not in the default list.
        run bench_load docs/bench/load $mr bench load --runs 45 --out docs/bench/load
        find docs/bench/load -type f -name '*.glb' -delete ;;
    *) echo "bench.sh: unknown bench '$b' (ao, ghost, tracking, scene, scene-unique, scene-instanced, multiview, map, measure, shadows, load)" >&2; exit 2 ;;
    esac
done
echo "bench.sh: wrote docs/bench/ at commit $commit ($dirty)" >&2
