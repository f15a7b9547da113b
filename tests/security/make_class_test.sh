#!/usr/bin/env bash
# deploy/security/make-class as docs/service.md shows it: which identities it makes, and for how
# long. Options stand anywhere (before, between, after the names; --days N or --days=N), and a
# command line that would make the wrong identities is refused (non-zero, saying why) before
# anything is made. Checked with the files themselves: the identity directories, the rigs each
# student's signed permissions name, and the certificates' end dates (openssl x509 -enddate).
# Exit 77 (skipped, saying why) without openssl.
#   tests/security/make_class_test.sh SOURCE_DIR
set -euo pipefail
make_class="$1/deploy/security/make-class"
command -v openssl >/dev/null || { echo "skipped: openssl not installed"; exit 77; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# The identity directories made under OUT, but for ca/, service/ and instructor/, sorted.
students() { (cd "$1" && for d in */; do d="${d%/}"; case "$d" in ca|service|instructor) ;; *) echo "$d" ;; esac; done | sort | paste -sd' '); }
# The rig partitions NAME's permissions let it read (the signed S/MIME text carries the XML).
reads() { sed -n 's:.*<subscribe>.*<partitions>\(.*\)</partitions></subscribe>.*:\1:p' "$1/permissions.p7s" | sed -e 's:</partition><partition>: :g' -e 's:</\{0,1\}partition>::g'; }
# Days from now to a certificate's end (openssl x509 -enddate), rounded.
days_left() {
  local end
  end="$(openssl x509 -enddate -noout -in "$1" | cut -d= -f2)"
  echo $(( ($(date -u -d "$end" +%s) - $(date -u +%s) + 43200) / 86400 ))
}
# run NAME ARGS...: make-class with ARGS (OUT is $work/NAME); its output in $work/NAME.log.
run() { local name="$1"; shift; "$make_class" "$@" >"$work/$name.log" 2>&1; }
expect_made() {  # expect_made NAME "STUDENTS " DAYS [ARGS...]
  local name="$1" want="$2" days="$3" before="$failures"; shift 3
  if ! run "$name" "$@"; then fail "make-class $* failed: $(cat "$work/$name.log")"; return; fi
  local got; got="$(students "$work/$name")"
  [[ "$got" == "$want" ]] || fail "make-class $*: students '$got', want '$want'"
  for who in ca/ca_cert service/identity instructor/identity alice/identity; do
    local left; left="$(days_left "$work/$name/$who.pem")"
    [[ "$left" == "$days" ]] || fail "make-class $*: $who.pem ends in $left days, want $days"
  done
  local until; until="$(sed -n 's:.*<not_after>\([^<]*\)</not_after>.*:\1:p' "$work/$name/alice/permissions.p7s")"
  local permission_days=$(( ($(date -u -d "$until" +%s) - $(date -u +%s) + 43200) / 86400 ))
  [[ "$permission_days" == "$days" ]] || fail "make-class $*: permissions end in $permission_days days, want $days"
  (( failures > before )) || echo "ok: make-class $* -> students: $got; certificates and permissions end in $days days"
}
expect_refused() {  # expect_refused NAME WORDS-THE-MESSAGE-HAS ARGS...
  local name="$1" says="$2"; shift 2
  if run "$name" "$@"; then fail "make-class $* was not refused: $(tail -1 "$work/$name.log")"; return; fi
  grep -q -- "$says" "$work/$name.log" || fail "make-class $*: the refusal does not say '$says': $(cat "$work/$name.log")"
  [[ ! -e "$work/$name" ]] || fail "make-class $*: refused, but made $work/$name"
  echo "ok: make-class $* -> refused: $(head -1 "$work/$name.log")"
}

# docs/service.md's invocation: --shared after the names.
expect_made doc "alice bob carol" 365 "$work/doc" alice bob carol:alice --shared demo
reads_alice="$(reads "$work/doc/alice")"
reads_carol="$(reads "$work/doc/carol")"
[[ " $reads_alice " == *" rig.demo "* ]] || fail "alice may not read the shared rig demo: $reads_alice"
[[ " $reads_carol " == *" rig.demo "* && " $reads_carol " == *" rig.alice "* ]] ||
  fail "carol may not read demo and alice: $reads_carol"
[[ " $(reads "$work/doc/bob") " != *" rig.alice "* ]] || fail "bob may read alice's rig"
grep -q "3 students (alice bob carol); valid 365 days" "$work/doc.log" || fail "summary: $(cat "$work/doc.log")"
echo "ok: alice reads: $reads_alice; carol reads: $reads_carol"

# --days after the names; --days=N before OUT with --shared=RIG between the names.
expect_made days_after "alice bob" 30 "$work/days_after" alice bob --days 30
expect_made between "alice bob" 7 --days=7 "$work/between" alice --shared=demo bob
[[ " $(reads "$work/between/bob") " == *" rig.demo "* ]] || fail "--shared=demo between the names not granted"

# What would make the wrong identities is refused, and nothing is made.
expect_refused unknown "unknown option '--bogus'" "$work/unknown" alice --bogus
expect_refused dash_name "unknown option '-x'" "$work/dash_name" alice -x
expect_refused days_missing "--days needs a value" "$work/days_missing" alice --days
expect_refused days_option "--shared needs a value" "$work/days_option" alice --shared --days 30
expect_refused days_twice "--days given twice" "$work/days_twice" alice --days 30 --days 60
expect_refused days_zero "must be a whole number" "$work/days_zero" alice --days 0
expect_refused watch_dash "watches '-x'" "$work/watch_dash" alice bob:-x
expect_refused double_dash "unknown option '--'" "$work/double_dash" alice -- -carol
expect_refused no_out "OUT, the directory to make, is missing" --days 30

if (( failures > 0 )); then echo "$failures check(s) failed"; exit 1; fi
echo "make-class: every documented form made the identities it names; every wrong form was refused"
