#!/usr/bin/env bash
# Leave-one-recording-out on your own labelled recordings (docs/your-robot.md):
# for each bag in DIR, train on the others (alone, and with N simulated trials) and evaluate
# the model on the bag left out, forest and baselines.
#
#   benchmarks/leave_one_out.sh DIR LABELS.csv OUT [N_SIM [TRAIN_OPTION...]]
#
# TRAIN_OPTIONs go to every train run (e.g. --trees 10 to skip the n_estimators search).
# OUT/<bag>/{alone,sim}.npz and evaluate reports OUT/<bag>/{alone,sim}/; the per-recording
# tables are collected in OUT/summary.md. The simulated trials are written once into
# OUT/sim (train reuses them for every fold). A model already trained is kept (the script
# resumes, and evaluates again); delete OUT to start again.
set -euo pipefail
dir=$1 labels=$2 out=$3 nsim=${4:-60}
shift 4 || shift $#
here=$(cd "$(dirname "$0")/.." && pwd)
cd_bin=${CONTACT_DETECTOR:-$here/.venv/bin/contact-detector}
mkdir -p "$out"
bags=$(cd "$dir" && ls -d *.bag)
summary=$out/summary.md
echo "# Leave one recording out: $dir ($nsim simulated trials in the 'sim' runs)" > "$summary"
for bag in $bags; do
  fold=$out/$bag
  mkdir -p "$fold/train"
  rm -f "$fold"/train/*
  for other in $bags; do
    [ "$other" = "$bag" ] || ln -s "$(cd "$dir" && pwd)/$other" "$fold/train/$other"
  done
  for kind in alone sim; do
    if [ ! -s "$fold/$kind.npz" ]; then
      extra=()
      [ "$kind" = sim ] && extra=(--with-sim "$nsim" --sim-dir "$out/sim")
      "$cd_bin" train "$fold/train" --labels "$labels" "${extra[@]}" "$@" \
        --out "$fold/$kind.npz" --no-events > "$fold/$kind.train.log" 2>&1
    fi
    "$cd_bin" evaluate "$dir/$bag" --labels "$labels" --model "$fold/$kind.npz" \
      --detector all --report "$fold/$kind" > "$fold/$kind.eval.log" 2>&1
    {
      echo; echo "## $bag, trained on the others ($kind)"; echo
      grep '^|' "$fold/$kind.eval.log" | tail -n 3
    } >> "$summary"
  done
done
echo "wrote $summary"
