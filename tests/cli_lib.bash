# Shared by the CLI tests (sourced, not a test itself): a scratch directory $T,
# a failure counter and check NAME EXPECTED_CODE NEEDLE -- command...
# (the command must exit with EXPECTED_CODE and print NEEDLE on stdout or stderr).
set -u
WOVEN=$1
SRC=$2
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
check() {
  local name=$1 want=$2 needle=$3
  shift 4
  "$@" >"$T/out" 2>"$T/err"
  local got=$?
  if [[ $got != "$want" ]] || { [[ -n $needle ]] && ! grep -qF -- "$needle" "$T/err" "$T/out"; }; then
    echo "FAIL $name: exit $got (wanted $want), output:"
    cat "$T/out" "$T/err"
    fails=$((fails + 1))
  else
    echo "ok   $name"
  fi
}
