#!/usr/bin/env bash
# Train the samplers of mixture-periodic on the joined corpus (../shared/data/mocap + ../shared/data/bandai)
# into motion2video/weights/*-bandai.safetensors, and compose mixture-periodic-bandai from them.
#
#   scripts/train_shipped_bandai.sh                  # all five, two lanes (one torch thread each)
#   STEPS_SCALE=0.1 scripts/train_shipped_bandai.sh  # a quick smoke run (10% of the steps)
#   ONLY="mtvae-add-bandai" scripts/train_shipped_bandai.sh
#   BASE_MINUTES=24 DLOW_MINUTES=10 scripts/train_shipped_bandai.sh   # wall-time budgets (a loaded machine)
#
# The recipes are those of scripts/train_shipped.sh (mtvae-add, mtvae-add-dlow, mixer-cvae, mixer-cvae-dlow),
# with the subject split (held_out "subjects", docs/data.md): training never sees the corpus's test subjects nor
# Bandai-Namco's skeleton groups 1B and 2C, so `evaluate --split subjects` and the corpus's test split both
# score these models on people they never saw. Bandai-Namco's files are CC BY-NC 4.0: every checkpoint written
# here is for non-commercial use (its card and its licence record say so).
# BASE_MINUTES / DLOW_MINUTES (0: none) give the base models and the DLow samplers a wall-time budget per run
# (TrainConfig.max_minutes: the learning rate follows whichever of steps and time is further along, and the run
# ends annealed when the budget is spent; the checkpoint and its card record the steps done). The shipped *-bandai
# checkpoints were trained with BASE_MINUTES=24 DLOW_MINUTES=10 on the shared 2-core machine under a load of
# about 14 processes, so they did fewer steps than the recipes (their cards say how many).
# Logs go to out/train_bandai/; the model cards are written by scripts/make_results.py card from the
# evaluations run afterwards (docs/results.md, "The samplers retrained with Bandai-Namco").
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PY:-.venv/bin/python}
MOCAP=${MOCAP:-../shared/data/mocap}
BANDAI=${BANDAI:-../shared/data/bandai}
WEIGHTS=${WEIGHTS:-motion2video/weights}
LOGS=${LOGS:-out/train_bandai}
STEPS_SCALE=${STEPS_SCALE:-1}
ONLY=${ONLY:-"mtvae-add-bandai mtvae-add-dlow-bandai mixer-cvae-bandai mixer-cvae-dlow-bandai mixture-periodic-bandai"}
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
mkdir -p "$WEIGHTS" "$LOGS"

BASE_MINUTES=${BASE_MINUTES:-0}
DLOW_MINUTES=${DLOW_MINUTES:-0}
DATA_SUBJECTS='"data": {"held_out": "subjects"}'
MTVAE_BODY='"model": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128, "motion_stats_weight": 100.0}'
TRAIN='"train": {"batch_size": 64, "lr": 0.001, "checkpoint_every": 500, "val_every": 500, "max_minutes": '$BASE_MINUTES'}'
MIXER_CVAE='"model": {"kl_weight": 0.01, "stats_weight": 1.0}, "data": {"held_out": "subjects"}, "train": {"batch_size": 64, "lr": 0.002, "checkpoint_every": 1000, "val_every": 1000, "max_minutes": '$BASE_MINUTES'}'
# DLow reuses its base checkpoint's data settings and split (apps/train.py), so it has no data section.
DLOW='"model": {"num_samples": 50}, "train": {"batch_size": 16, "lr": 0.0005, "checkpoint_every": 200, "val_every": 200, "augment": true, "max_minutes": '$DLOW_MINUTES'}'

steps() { "$PY" -c "import sys; print(max(1, round($1 * float(sys.argv[1]))))" "$STEPS_SCALE"; }

# train_one NAME MODEL STEPS CONFIG [EXTRA ARGS...]
train_one() {
  local name=$1 model=$2 n; n=$(steps "$3"); local config=$4; shift 4
  case " $ONLY " in *" $name "*) ;; *) return 0 ;; esac
  local out="$WEIGHTS/$name.safetensors"
  local cmd="motion2video train --model $model --data $MOCAP --data $BANDAI -o $out --steps $n --seed 0 --config '$config' $*"
  echo "[$(date +%T)] $name: $cmd" | tee "$LOGS/$name.command"
  local t0=$SECONDS
  "$PY" -m motion2video.cli train --model "$model" --data "$MOCAP" --data "$BANDAI" -o "$out" --steps "$n" --seed 0 \
      --config "$config" --no-progress "$@" > "$LOGS/$name.log" 2>&1
  rm -f "$WEIGHTS/$name.last.safetensors" "$WEIGHTS/$name.last.optim.safetensors"
  echo "[$(date +%T)] $name done in $((SECONDS - t0)) s ($(du -h "$out" | cut -f1))"
}

lane_a() {
  train_one mtvae-add-bandai mtvae-add 4000 "{$MTVAE_BODY, $DATA_SUBJECTS, $TRAIN}"
  train_one mtvae-add-dlow-bandai dlow 600 "{$DLOW}" --base "$WEIGHTS/mtvae-add-bandai.safetensors"
}

lane_b() {
  train_one mixer-cvae-bandai mixer-cvae 6000 "{$MIXER_CVAE}"
  train_one mixer-cvae-dlow-bandai dlow 600 "{$DLOW}" --base "$WEIGHTS/mixer-cvae-bandai.safetensors"
}

start=$SECONDS
lane_a & a=$!
lane_b & b=$!
status=0
wait $a || status=1
wait $b || status=1
case " $ONLY " in *" mixture-periodic-bandai "*)
  if [ $status -eq 0 ]; then
    "$PY" scripts/make_mixture.py "$WEIGHTS/mtvae-add-dlow-bandai.safetensors" "$WEIGHTS/mixer-cvae-dlow-bandai.safetensors" \
        mirror-periodic --shares 19,19,12 -o "$WEIGHTS/mixture-periodic-bandai.safetensors" \
        > "$LOGS/mixture-periodic-bandai.log" 2>&1 || status=1
    echo "[$(date +%T)] mixture-periodic-bandai composed (status $status)"
  fi ;;
esac
echo "all done in $(( (SECONDS - start) / 60 )) min (status $status); logs in $LOGS"
exit $status
