#!/usr/bin/env bash
# mpirun with the flags this project needs everywhere: root allowed, oversubscription allowed
# (more ranks than cores on small machines), and --quiet: a rank's own one-line error is the
# whole report (no Open MPI notice about a non-zero exit status). Usage:
#   bash jobs/mpirun.sh -n 2 python -m pdfem ...
# or from a job script (jobs/pbs.sh):   . jobs/mpirun.sh; pdfem_mpirun -n 2 python -m pdfem ...
# The status is mpirun's (2 bad input, 3 a guard, ...), with SIGTERM as described next.
#
# Signals. Open MPI 4.1's mpirun takes SIGTERM, SIGINT and SIGHUP as "abort the job": it sends
# the ranks SIGCONT, a second later SIGTERM, a second after that SIGKILL (the MCA parameter
# odls_base_sigkill_timeout, 1 s), and exits 1 even when every rank exited 0. A second such
# signal while it does so makes it exit at once, leaving the ranks running, unsignalled. It
# refuses to forward SIGTERM (ess_base_forward_signals), but passes SIGUSR1 and SIGUSR2 on to
# every rank at once and then exits with the ranks' status. So:
# - mpirun starts with SIGTERM and SIGINT blocked (a mask survives exec; Open MPI clears it in
#   the ranks): a signal sent to every process of the job (the scheduler's at the time limit,
#   Ctrl-C, a kill of the process group) reaches the ranks and this script, never mpirun;
# - the first SIGTERM this script gets goes to mpirun as SIGUSR1, which every rank gets at once:
#   `python -m pdfem run` takes it as SIGTERM (finishes the step, writes <run>.ckpt.h5, exits
#   0, however long that takes) and mpirun exits 0. Later SIGTERMs are ignored;
# - the first SIGINT goes to mpirun as SIGHUP: it aborts the job as on Ctrl-C; its status.
#   Later ones are ignored (mpirun ends the job within 2 s; SIGHUP or SIGKILL still end it);
# - the script names a fresh file in PDFEM_STATUS_FILE that `python -m pdfem run` writes (rank
#   0, once every rank has ended cleanly). When mpirun's status is not 0 after a SIGTERM while
#   that file was written (mpirun or a remote node's daemon got the signal and aborted after the
#   ranks had stopped), the status is 0. Only pdfem run writes it; rank 0 must see the file
#   (it is under $TMPDIR, and rank 0 runs on mpirun's node unless a hostfile says otherwise).
# A signal that comes before the ranks' Python has started pdfem (well under a second after the
# start) ends them, with a non-zero status and no checkpoint.

# mpirun's launcher: SIGTERM and SIGINT blocked, then exec
_PDFEM_BLOCK='import os, signal, sys
signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM, signal.SIGINT})
try:
    os.execvp(sys.argv[1], sys.argv[1:])
except OSError as exc:
    sys.exit(f"jobs/mpirun.sh: {sys.argv[1]}: {exc.strerror}")'

# Send mpirun the signal asked for, each kind once (pid known)
_pdfem_forward() {
  [ -n "$_pdfem_pid" ] || return 0
  case "$_pdfem_want:$_pdfem_sent" in
    USR1:) _pdfem_sent=USR1; kill -USR1 "$_pdfem_pid" 2>/dev/null || : ;;
    HUP:|HUP:USR1) _pdfem_sent=HUP; kill -HUP "$_pdfem_pid" 2>/dev/null || : ;;
  esac
}

pdfem_mpirun() {
  local _pdfem_pid="" _pdfem_want="" _pdfem_sent="" _pdfem_got="" termed="" status="" rc
  local traps launch=()
  traps=$(trap -p TERM INT)
  trap '_pdfem_got=1; termed=1; [ -n "$_pdfem_want" ] || _pdfem_want=USR1; _pdfem_forward' TERM
  trap '_pdfem_got=1; _pdfem_want=HUP; _pdfem_forward' INT
  status=$(mktemp "${TMPDIR:-/tmp}/pdfem-status.XXXXXX" 2>/dev/null) || status=""
  launch=("$(command -v python3 || command -v python)" -I -S -c "$_PDFEM_BLOCK")
  # In the background so that the traps run at once; stdin kept (not /dev/null)
  PDFEM_STATUS_FILE=$status "${launch[@]}" mpirun --allow-run-as-root --oversubscribe --quiet \
      --mca btl_vader_single_copy_mechanism none -x PDFEM_STATUS_FILE "$@" <&0 &
  _pdfem_pid=$!
  _pdfem_forward
  # wait returns early when a trapped signal comes; then wait again (bash keeps the status of
  # a process that ended meanwhile)
  while :; do
    _pdfem_got=""
    rc=0
    wait "$_pdfem_pid" || rc=$?
    [ -n "$_pdfem_got" ] || break
  done
  if [ "$rc" -ne 0 ] && [ -n "$termed" ] && [ -n "$status" ] && [ -s "$status" ]; then
    rc=0
  fi
  [ -z "$status" ] || rm -f "$status"
  trap - TERM INT
  eval "$traps"
  return "$rc"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  pdfem_mpirun "$@"
  exit $?
fi
