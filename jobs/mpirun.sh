#!/usr/bin/env bash
# mpirun with the flags this project needs everywhere: root allowed, oversubscription allowed
# (more ranks than cores on small machines). Usage: jobs/mpirun.sh -n 2 python -m pdfem ...
exec mpirun --allow-run-as-root --oversubscribe --mca btl_vader_single_copy_mechanism none "$@"
