#!/bin/bash
# One model on several nodes: a single ancf-solve run whose MPI ranks span the nodes of one SLURM
# allocation (ancf-sweep --slurm writes job arrays of small independent runs instead).
# docs/parallel.md, "Beyond one machine", explains the choices below.
#
#   sbatch --nodes=4 --ntasks-per-node=16 scripts/slurm_one_model.sh configs/my_muscle.yaml
#   ANCF_VENV=/path/to/.venv OUT=results/my_muscle sbatch ... scripts/slurm_one_model.sh CONFIG [PETSc options]
#
#SBATCH --job-name=ancf-one-model
#SBATCH --nodes=4                 # override on the sbatch command line
#SBATCH --ntasks-per-node=16      # one rank per physical core
#SBATCH --cpus-per-task=1         # each rank is single-threaded (BLAS too)
#SBATCH --mem=0                   # the whole memory of each node (MUMPS's multiplier factor grows)
#SBATCH --time=02:00:00
#SBATCH --signal=TERM@120         # ask ancf-solve to stop cleanly 2 min before the limit
#SBATCH --output=slurm-%j.out
set -euo pipefail

CONFIG=${1:?usage: sbatch [--nodes N --ntasks-per-node M] slurm_one_model.sh CONFIG.yaml [PETSc options]}
shift
# The environment: ANCF_VENV, else the .venv of the directory sbatch was run from (the project;
# under sbatch "$0" is SLURM's copy of this script in its spool directory, which says nothing
# about where the project is), else the .venv beside this script (run with bash directly).
if [ -n "${ANCF_VENV:-}" ]; then
  VENV=$ANCF_VENV
elif [ -n "${SLURM_SUBMIT_DIR:-}" ] && [ -x "$SLURM_SUBMIT_DIR/.venv/bin/ancf-solve" ]; then
  VENV=$SLURM_SUBMIT_DIR/.venv
else
  VENV=$(cd "$(dirname "$0")/.." && pwd)/.venv
fi
if [ ! -x "$VENV/bin/ancf-solve" ]; then
  echo "slurm_one_model.sh: no ancf-solve in $VENV/bin: submit from the project directory" \
       "(cd ancf-petsc && sbatch scripts/slurm_one_model.sh ...) or set ANCF_VENV=/path/to/.venv" >&2
  exit 2
fi
OUT=${OUT:-results/$(basename "${CONFIG%.*}")_${SLURM_JOB_ID:-local}}
mkdir -p "$OUT"

# one thread per rank: the dense fascicle factors and MUMPS's fronts call BLAS, and threads would
# compete with the ranks placed on the same cores
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1

# The fascicle-parallel solver keeps every fascicle whole on one rank (partition 'beams');
# ranks beyond the number of fascicles get no work.  The direct solver (small scenes) takes the
# config's partition.  solver.linear: auto chooses between them (docs/parallel.md).
# -log_view writes PETSc's time, flop and message summary (per stage and event) for the run.
# srun starts the ranks (PMIx/PMI2 as the cluster provides); with Open MPI's own launcher use
#   mpirun --map-by ppr:${SLURM_NTASKS_PER_NODE}:node --bind-to core
# instead.  ancf-solve stops at the next safe point on the SIGTERM above, keeps every
# converged load level in $OUT, and exits 143 (docs/running.md, "Signals").
# ANCF_LAUNCH replaces srun, e.g. ANCF_LAUNCH="mpirun -n 2" bash scripts/slurm_one_model.sh ...
# to try the script on a workstation (tests/workflows/test_slurm_one_model.py does).
read -r -a LAUNCH <<< "${ANCF_LAUNCH:-srun --kill-on-bad-exit=1 --cpu-bind=cores}"
"${LAUNCH[@]}" "$VENV/bin/ancf-solve" "$CONFIG" --output-dir "$OUT" \
    -log_view ":$OUT/log_view.txt" "$@"
