#!/usr/bin/env bash
# mpirun with the flags this project needs everywhere: root allowed, oversubscription allowed
# (more ranks than cores on small machines), and --quiet: a rank's own one-line error is the
# whole report (no Open MPI notice about a non-zero exit status). Usage:
# jobs/mpirun.sh -n 2 python -m pdfem ...
exec mpirun --allow-run-as-root --oversubscribe --quiet --mca btl_vader_single_copy_mechanism none \
    "$@"
