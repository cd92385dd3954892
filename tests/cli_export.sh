#!/usr/bin/env bash
# mrcheck export on a small session (tests/data/export/session, written by
# mr_export_mark_write as test_export does): BCF 2.1 and 3.0 and the report
# are written; bad input (no marks, a missing snapshot, an unwritable
# output, a bad --bcf-version) gives one line, a non-zero exit and nothing
# half-written; a torn last line is skipped with one warning. No GPU.
# Usage: cli_export.sh MRCHECK TMPDIR.
set -u
mr=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
# shellcheck source=common_cli.sh
. "$(dirname "$0")/common_cli.sh"
data=$(dirname "$0")/data/export/session
cp -r "$data" "$tmp/session"

if "$mr" export "$tmp/session" --bcf "$tmp/a.bcf" >"$tmp/a.log" 2>&1 && [ -s "$tmp/a.bcf" ]; then ok; else bad "export --bcf: $(cat "$tmp/a.log")"; fi
if unzip -l "$tmp/a.bcf" >"$tmp/a.list" 2>&1; then
  [ "$(grep -cE ' [0-9a-f-]{36}/$' "$tmp/a.list")" -eq 2 ] && ok || bad "2.1: not two topic folders: $(cat "$tmp/a.list")"
  grep -q ' bcf.version$' "$tmp/a.list" && ok || bad "2.1: no bcf.version"
  grep -q 'extensions.xml' "$tmp/a.list" && bad "2.1 has extensions.xml" || ok
else
  bad "unzip -l a.bcf failed"
fi
if "$mr" export "$tmp/session" --bcf "$tmp/b.bcf" --bcf-version 3.0 >"$tmp/b.log" 2>&1; then ok; else bad "export 3.0: $(cat "$tmp/b.log")"; fi
unzip -p "$tmp/b.bcf" bcf.version 2>/dev/null | grep -q 'VersionId="3.0"' && ok || bad "3.0: bcf.version"
unzip -l "$tmp/b.bcf" 2>/dev/null | grep -q ' extensions.xml$' && ok || bad "3.0: no extensions.xml"
if "$mr" export "$tmp/session" --html "$tmp/report" >"$tmp/r.log" 2>&1 && [ -s "$tmp/report/index.html" ] &&
   [ -s "$tmp/report/report.md" ] && [ -s "$tmp/report/img/mark_1_photo.png" ]; then ok; else bad "export --html: $(cat "$tmp/r.log")"; fi

# Bad input: one line each, nothing left behind.
mkdir -p "$tmp/empty"
expect_fail no_marks "$tmp/none.bcf" -- "$mr" export "$tmp/empty" --bcf "$tmp/none.bcf"
grep -q "no marks" "$tmp/no_marks.err" && ok || bad "no marks: $(cat "$tmp/no_marks.err")"
: >"$tmp/empty/annotations.jsonl"
expect_fail no_marks_empty "$tmp/none.bcf" -- "$mr" export "$tmp/empty" --bcf "$tmp/none.bcf"
cp -r "$data" "$tmp/missing"
rm "$tmp/missing/snapshots/mark_0002_frame.png"
expect_fail missing_snapshot "$tmp/m.bcf" -- "$mr" export "$tmp/missing" --bcf "$tmp/m.bcf"
grep -q "mark 2" "$tmp/missing_snapshot.err" && ok || bad "missing snapshot: $(cat "$tmp/missing_snapshot.err")"
expect_fail missing_snapshot_html "$tmp/mr" -- "$mr" export "$tmp/missing" --html "$tmp/mr"
expect_fail unwritable "" -- "$mr" export "$tmp/session" --bcf "$tmp/no/such/dir/x.bcf"
ls "$tmp/no" >/dev/null 2>&1 && bad "unwritable: made folders" || ok
expect_fail bad_version "$tmp/v.bcf" -- "$mr" export "$tmp/session" --bcf "$tmp/v.bcf" --bcf-version 2.2
expect_fail no_output "" -- "$mr" export "$tmp/session"
mkdir -p "$tmp/foreign" && echo keep >"$tmp/foreign/keep.txt"
expect_fail foreign_dir "" -- "$mr" export "$tmp/session" --html "$tmp/foreign"
[ -f "$tmp/foreign/keep.txt" ] && [ ! -e "$tmp/foreign/index.html" ] && ok || bad "foreign folder touched"
# A torn last line: the marks before it, one warning.
cp -r "$data" "$tmp/torn"
printf '{"type":"discrepancy","note":"tor' >>"$tmp/torn/annotations.jsonl"
if "$mr" export "$tmp/torn" --bcf "$tmp/t.bcf" >"$tmp/t.out" 2>"$tmp/t.err"; then ok; else bad "torn: $(cat "$tmp/t.err")"; fi
[ "$(wc -l <"$tmp/t.err")" -eq 1 ] && grep -q torn "$tmp/t.err" && ok || bad "torn: stderr $(cat "$tmp/t.err")"
[ "$(unzip -l "$tmp/t.bcf" 2>/dev/null | grep -cE ' [0-9a-f-]{36}/$')" -eq 2 ] && ok || bad "torn: topics"
# bcf list / bcf answer on the archive written above: the answer keeps the
# topic and adds the comment and status; bad input fails with one line.
if "$mr" bcf list "$tmp/a.bcf" >"$tmp/list.out" 2>"$tmp/list.err"; then ok; else bad "bcf list: $(cat "$tmp/list.err")"; fi
[ "$(wc -l <"$tmp/list.out")" -eq 2 ] && grep -q $'^1\t[0-9a-f-]\{36\}\t' "$tmp/list.out" && ok || bad "bcf list: $(cat "$tmp/list.out")"
"$mr" bcf answer "$tmp/a.bcf" --topic 1 --comment "fixed on site" --status Closed --out "$tmp/ans.bcf" \
  >"$tmp/ans.log" 2>&1 && [ -s "$tmp/ans.bcf" ] && ok || bad "bcf answer: $(cat "$tmp/ans.log")"
c0=$(head -1 "$tmp/list.out" | grep -o 'comments [0-9]*' | cut -d' ' -f2)
"$mr" bcf list "$tmp/ans.bcf" >"$tmp/ans.list" 2>&1 && head -1 "$tmp/ans.list" | grep -q $'\tClosed\t.*comments '$((c0 + 1)) && ok ||
  bad "answered topic: $(cat "$tmp/ans.list")"
unzip -p "$tmp/ans.bcf" '*/markup.bcf' 2>/dev/null | grep -q 'fixed on site' && ok || bad "bcf answer: no comment in markup"
[ "$(cut -f2 "$tmp/ans.list")" = "$(cut -f2 "$tmp/list.out")" ] && ok || bad "bcf answer changed the GUIDs"
expect_fail answer_no_out "" -- "$mr" bcf answer "$tmp/a.bcf" --topic 1
expect_fail answer_bad_topic "$tmp/bt.bcf" -- "$mr" bcf answer "$tmp/a.bcf" --topic 9 --out "$tmp/bt.bcf"
expect_fail answer_no_snapshot "$tmp/ns.bcf" -- "$mr" bcf answer "$tmp/a.bcf" --topic 1 --snapshot "$tmp/none.png" --out "$tmp/ns.bcf"
expect_fail list_missing "" -- "$mr" bcf list "$tmp/none.bcf"
cli_finish cli_export
