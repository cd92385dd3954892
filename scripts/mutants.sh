#!/usr/bin/env bash
# Plants known bugs one at a time and checks that the test suite catches
# each: the bugs a reviewer planted for issue 10, and variants of them.
# For every mutant: the source is changed (a literal text replacement that
# must match exactly once), the test targets the mutant names are rebuilt
# in build/ (the same build for every mutant, so only the mutated file
# recompiles), the named tests run through ctest-strict.sh (so a skip
# counts as caught, as in scripts/test.sh), and the source is restored.
# Prints one line per mutant and exits non-zero if any mutant survived,
# does not compile, or names text that is no longer in its file.
#   bash scripts/mutants.sh            # all mutants
#   bash scripts/mutants.sh flip rot   # only those whose name contains a word
#   bash scripts/mutants.sh --check    # only that every entry still matches
#   bash scripts/mutants.sh --changed [BASE]
#       # only the mutants a change since BASE can affect (CI runs this;
#       # docs/development.md gives the rule and how BASE is chosen)
# Needs a configured build/ (bash scripts/build.sh) and a clean tree for the
# files it touches.
set -uo pipefail
cd "$(dirname "$0")/.."
[ -f build/CMakeCache.txt ] || { echo "mutants: run bash scripts/build.sh first" >&2; exit 2; }

# The list: scripts/mutants.d/MODULE.list, one file per module so that
# work on different modules adds entries without touching the same lines.
# Each line: name|file|text|replacement|ctest -R regex (\n in text or
# replacement is a newline; a line starting with # is a comment).
mutants=$(cat scripts/mutants.d/*.list | grep -v -e '^#' -e '^[[:space:]]*$')

# --check: only verify that every mutant's text is in its file exactly once
# (no build, seconds): a stale entry fails, it is never skipped.
if [ "${1:-}" = --check ]; then
  bad=0
  while IFS='|' read -r name file text repl tests; do
    [ -n "$name" ] || continue
    if ! FROM="$text" perl -0ne '
          my $f = $ENV{FROM} =~ s/\\n/\n/gr;
          my $n = () = /\Q$f\E/g;
          exit($n == 1 ? 0 : 1);' "$file" 2>/dev/null; then
      echo "ERROR    $name: the text to mutate in $file is not there exactly once (update the list)"
      bad=$((bad + 1))
    fi
  done <<<"$mutants"
  echo "mutants --check: $bad stale of $(grep -c . <<<"$mutants")"
  [ $bad -eq 0 ]
  exit
fi

# --changed [BASE]: the mutants a change since BASE can affect. BASE is the
# argument, else $MR_MUTANTS_BASE, else the commit in .ci/mutants-base (the
# last commit on which every mutant ran and was caught). The change is git
# diff from merge-base(BASE, HEAD) to the working tree. A mutant runs when
# its file changed; when a test its regex selects changed (tests/NAME.c,
# .cc, .sh or .py: a weakened test must still catch it); when its own entry
# is new or edited; or when a header that its file or one of those tests
# compiles changed (from the compiler's dependency files in build/, so
# build/ must have been built; a shader include counts for the shaders that
# include it, directly or not). Every mutant runs when BASE is not in this
# clone's history (a shallow clone, a rewritten main) or when a header
# changed and build/ has no dependency files: running more is safe, fewer
# is not. Those whose file changed run first, so that a time budget
# (MR_MUTANTS_DEADLINE, below) spends itself on the likeliest ones.
only=""
if [ "${1:-}" = --changed ]; then
  base=${2:-${MR_MUTANTS_BASE:-$(cat .ci/mutants-base 2>/dev/null || true)}}
  base=${base%%[[:space:]]*}
  if [ -z "$base" ] || ! git cat-file -e "$base^{commit}" 2>/dev/null || ! mb=$(git merge-base "$base" HEAD 2>/dev/null); then
    echo "mutants: base '${base:-none}' is not in this clone's history: running every mutant"
    only=all
  else
    changed=$( { git diff --name-only "$mb"; git ls-files --others --exclude-standard; } | sort -u)
    echo "mutants: changes since ${base:0:12} (merge-base ${mb:0:12}): $(grep -c . <<<"$changed" || true) file(s)"
    # Sources (repository paths) that compile a changed header.
    users=""
    headers=$(grep -E '^(lib|tests|app)/.*\.(h|hh|hpp)$|^shaders/[^/]+\.h$' <<<"$changed" || true)
    if [ -n "$headers" ]; then
      mapfile -t deps < <(find build -name '*.o.d' 2>/dev/null)
      if [ ${#deps[@]} -eq 0 ]; then
        echo "mutants: headers changed and build/ has no dependency files: running every mutant"
        only=all
      else
        for h in $headers; do
          for d in $(grep -lF -- "/$h" "${deps[@]}" 2>/dev/null); do
            # the object's source is the first prerequisite in its depfile
            users="$users"$'\n'"$(awk 'NR == 1 { print $2; exit }' "$d" | sed -E 's#^(.*/)?((lib|tests|app)/)#\2#')"
          done
        done
      fi
    fi
    # Shaders that pull in a changed shader header or include, transitively.
    todo=$(grep -E '^shaders/[^/]+\.(h|glsl)$' <<<"$changed" || true)
    seen=""
    while [ -n "$todo" ]; do
      next=""
      for f in $todo; do
        [[ "$seen" == *" $f "* ]] && continue
        seen="$seen $f "
        users="$users"$'\n'"$f"
        for g in $(grep -lF -- "#include \"${f#shaders/}\"" shaders/* 2>/dev/null); do next="$next $g"; done
      done
      todo=$next
    done
    if [ "$only" != all ]; then
      # Entries new or edited since the merge-base (the list then was either
      # scripts/mutants.d/ or a here-document inside this script).
      was=$( { for f in $(git ls-tree --name-only "$mb" scripts/mutants.d/ 2>/dev/null); do git show "$mb:$f"; done
               git show "$mb:scripts/mutants.sh" 2>/dev/null | sed -n "/^mutants=\$(cat <<'LIST'/,/^LIST\$/p"; } | grep -v '^#' )
      newlines=$(grep -vxF -f <(printf '%s\n' "$was") <<<"$mutants" | cut -d'|' -f1)
      changed_tests=$(sed -nE 's#^tests/([A-Za-z0-9_]+)\.(c|cc|sh|py)$#\1#p' <<<"$changed")
      test_users=$(sed -nE 's#^tests/([A-Za-z0-9_]+)\.(c|cc)$#\1#p' <<<"$users")
      first="" later=""
      while IFS='|' read -r name file text repl tests; do
        [ -n "$name" ] || continue
        hit=0
        { grep -qxF -- "$file" <<<"$changed" || grep -qxF -- "$name" <<<"$newlines"; } && hit=1
        if [ $hit -eq 0 ]; then
          grep -qxF -- "$file" <<<"$users" && hit=2
          [ -n "$changed_tests" ] && grep -qE -- "$tests" <<<"$changed_tests" && hit=2
          [ -n "$test_users" ] && grep -qE -- "$tests" <<<"$test_users" && hit=2
        fi
        [ $hit -eq 1 ] && first="$first $name"
        [ $hit -eq 2 ] && later="$later $name"
      done <<<"$mutants"
      only="$first$later"
      [ -n "$only" ] || { echo "mutants: no mutant's file, test, header or entry changed: nothing to run"; exit 0; }
      echo "mutants: to run ($(wc -w <<<"$only")):$only"
      # Run them in that order: the list, reordered.
      mutants=$(for n in $only; do grep -m1 "^$n|" <<<"$mutants"; done)
    fi
  fi
  set --
  [ -z "${MR_MUTANTS_DRY:-}" ] || exit 0
fi

# MR_MUTANTS_DEADLINE (seconds since the epoch): no mutant starts after it;
# the ones left are listed as not run. CI sets it so that the suite and the
# mutants together end inside CI's time limit.
deadline=${MR_MUTANTS_DEADLINE:-}
notrun=""

backup=$(mktemp -d)
current=""
restore() {
  if [ -n "$current" ]; then cp "$backup/orig" "$current"; current=""; fi
}
trap 'restore; rm -rf "$backup"' EXIT
trap 'exit 130' INT TERM

# Each mutant's tests get a time limit: three times their slowest
# unmutated run (ctest's cost data from the suite's run in build/) plus a
# minute. A mutant that makes a test run that long (an ignored --frames,
# a loop that no longer ends) is caught by the limit instead of costing
# CI its time; without cost data ctest's default applies.
declare -A cost=()
if [ -f build/Testing/Temporary/CTestCostData.txt ]; then
  while read -r t _ c; do
    [ "$t" = "---" ] && break
    [ -n "${c:-}" ] && cost[$t]=$c
  done <build/Testing/Temporary/CTestCostData.txt
fi
all_tests=$(ctest --test-dir build -N 2>/dev/null | sed -n 's/^ *Test *#[0-9]*: //p')
time_limit() {
  local t slow=""
  for t in $(grep -E -- "$1" <<<"$all_tests"); do
    [ -n "${cost[$t]:-}" ] || continue
    slow=$(awk -v a="${slow:-0}" -v b="${cost[$t]}" 'BEGIN { print (b > a ? b : a) }')
  done
  [ -n "$slow" ] && awk -v s="$slow" 'BEGIN { printf "%d", 3 * s + 60 }'
}

survived=0 caught=0 built=""
start=$(date +%s)
while IFS='|' read -r name file text repl tests; do
  [ -n "$name" ] || continue
  if [ -n "$only" ] && [ "$only" != all ]; then
    [[ " $only " == *" $name "* ]] || continue
  fi
  if [ $# -gt 0 ]; then
    want=0
    for w in "$@"; do case $name in *"$w"*) want=1 ;; esac; done
    [ $want -eq 1 ] || continue
  fi
  if [ -n "$deadline" ] && [ "$(date +%s)" -ge "$deadline" ]; then notrun="$notrun $name"; continue; fi
  if ! git diff --quiet -- "$file"; then echo "mutants: $file has uncommitted changes; commit them first" >&2; exit 2; fi
  cp "$file" "$backup/orig"
  current=$file
  if ! FROM="$text" TO="$repl" perl -0pi -e '
        my ($f, $t) = map { s/\\n/\n/gr } ($ENV{FROM}, $ENV{TO});
        my $n = () = /\Q$f\E/g;
        die "matches $n times, want 1\n" unless $n == 1;
        s/\Q$f\E/$t/;' "$file"; then
    echo "ERROR    $name: the text to mutate in $file is not there exactly once (update the list)"
    restore
    survived=$((survived + 1))
    continue
  fi
  # Build only what the named tests run when the regex names them exactly
  # (^name$ or ^(a|b)$; cli_* scripts run mrcheck); otherwise everything.
  targets=""
  if [[ $tests =~ ^\^\(?([A-Za-z0-9_|]+)\)?\$$ ]]; then
    for t in ${BASH_REMATCH[1]//|/ }; do
      case $t in
        cli_* | module_map | header_alone_*) targets="$targets mrcheck" ;;
        *) targets="$targets $t" ;;
      esac
    done
    # test_track_retrack runs the binary too (tests/CMakeLists.txt)
    [[ " $targets " == *" test_track_retrack "* ]] && targets="$targets mrcheck"
  fi
  if [ -n "$targets" ]; then build_args=(--target $targets); else build_args=(); fi
  built="$built ${targets:-all}"
  if ! cmake --build build -j"$(nproc)" "${build_args[@]}" >"$backup/build.log" 2>&1; then
    echo "ERROR    $name: the mutant does not compile"
    tail -n 5 "$backup/build.log"
    restore
    survived=$((survived + 1))
    continue
  fi
  limit=$(time_limit "$tests")
  if bash scripts/ctest-strict.sh build -R "$tests" ${limit:+--timeout "$limit"} >"$backup/test.log" 2>&1; then
    echo "SURVIVED $name ($file): tests '$tests' still pass"
    survived=$((survived + 1))
  else
    why=$(grep -E "CHECK failed|FAIL:|FAILED|SKIPPED|\*\*\*Timeout" "$backup/test.log" | cut -c1-200 | head -n 3 | paste -sd "|" -)
    echo "caught   $name: $why"
    caught=$((caught + 1))
  fi
  restore
done <<<"$mutants"

# A hidden EGL (no vendor library) must fail the suite, not skip it.
if [ -n "$deadline" ] && [ "$(date +%s)" -ge "$deadline" ]; then
  [ $# -eq 0 ] && notrun="$notrun egl_hidden"
elif { [ $# -eq 0 ] && { [ -z "$only" ] || [ "$only" = all ] || [[ " $only " == *" gl_"* ]]; }; } || [[ " $* " == *" egl"* ]]; then
  if __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent bash scripts/ctest-strict.sh build -R '^(test_render|cli_render)$' >"$backup/test.log" 2>&1; then
    echo "SURVIVED egl_hidden: the suite passes without EGL"
    survived=$((survived + 1))
  else
    echo "caught   egl_hidden: $(grep -m1 -E "FAILED|SKIPPED" "$backup/test.log" | cut -c1-200)"
    caught=$((caught + 1))
  fi
fi

# Rebuild what was built from a mutant (the restored sources are newer).
echo "rebuilding the unmutated tree ..."
if [[ " $built " == *" all "* ]] || [ -z "$built" ]; then
  cmake --build build -j"$(nproc)" >/dev/null 2>&1
else
  # shellcheck disable=SC2086
  cmake --build build -j"$(nproc)" --target $(tr ' ' '\n' <<<"$built" | sort -u | paste -sd ' ') >/dev/null 2>&1
fi
echo "mutants: $caught caught, $survived survived or broken ($(($(date +%s) - start)) s)"
if [ -n "$notrun" ]; then
  echo "mutants: NOT RUN, the time budget was spent ($(wc -w <<<"$notrun")):$notrun"
fi
[ $survived -eq 0 ]
