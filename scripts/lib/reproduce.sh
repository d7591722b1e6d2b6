# Shared by scripts/reproduce-*.sh (sourced, not run): the pieces every reproduction script has in
# common. Each function takes the calling script's name first, for its messages.
#
#   reproduce_prepare NAME          needs ROOT; sets BIN, checks the programs a live recording and a
#                                   replay need, creates OUT (a fresh /tmp/omnislam-NAME.XXXXXX when
#                                   empty), puts BIN on PATH and sets URL to a private multicast port
#   reproduce_record NAME LAUNCH SEED SPEEDUP REC WHAT
#                                   records one seed with omnislam-launch unless REC already exists

reproduce_prepare() {
  local name="$1" t
  BIN="${OMNISLAM_BUILD_DIR:-$ROOT/build}/bin"
  for t in omnislam-launch omnislam-slam omnislam-eval omnislam-sim omnislam-capture omnislam-odometry omnislam-features omnislam-record; do
    [ -x "$BIN/$t" ] || { echo "$name: $BIN/$t missing: run scripts/build.sh first" >&2; exit 2; }
  done
  [ -n "$OUT" ] || OUT="$(mktemp -d "/tmp/omnislam-$name.XXXXXX")"
  mkdir -p "$OUT"
  export PATH="$BIN:$PATH"
  # A private multicast port (ttl=0: never leaves this machine) so that other runs do not cross.
  local port=$((20000 + $$ % 20000))
  URL="udpm://239.255.76.67:${port}?ttl=0&recv_buf_size=4194304"
}

reproduce_record() {
  local name="$1" launch="$2" seed="$3" speedup="$4" rec="$5" what="$6"
  [ -s "$rec" ] && return 0
  echo "$name: seed $seed: recording $what at ${speedup}x ..." >&2
  # Into REC.part, renamed only when the launcher says the scenario ran to its end (it exits
  # non-zero when a process failed, 128 + signal when interrupted): a later run with the same
  # OUT would otherwise take a partial recording for a finished one.
  "$BIN/omnislam-launch" "$launch" --url "$URL" --set "seed=$seed" --set "speedup=$speedup" --log-file "$rec.part" \
    > "$OUT/launch-seed$seed.txt" 2>&1 || {
    rm -f "$rec.part"
    echo "$name: seed $seed: the launch failed or was interrupted, see $OUT/launch-seed$seed.txt" >&2
    exit 1
  }
  mv "$rec.part" "$rec"
}
