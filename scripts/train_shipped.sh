#!/usr/bin/env bash
# Train the shipped motion checkpoints into motion2video/weights/, each with a model card
# (weights/<name>.md: command, data, steps, wall time, held-out metrics).
#
#   scripts/train_shipped.sh                 # all nine, two lanes (one torch thread each)
#   STEPS_SCALE=0.1 scripts/train_shipped.sh # a quick smoke run (10% of the steps)
#   scripts/train_shipped.sh --bandai        # the *-bandai samplers on the joined corpus (below)
#   ONLY="mtvae-add lcpvae" scripts/train_shipped.sh
#
# These step counts are the ones the shipped checkpoints were trained with (their model cards record the
# exact commands). Two lanes side by side, one torch thread each. Measured on the shared 2-core machine
# (2026-11-25, wall time per model, training + held-out evaluation + card): lane A mtvae-add 4000 steps 14 min,
# mtvae-add-dlow 600 steps 7 min, behavior 4000 steps 14 min; lane B lcpvae 3000 steps 7 min, mtvae-add-2d
# 2500 steps 8 min, mtvae-add-face 1200 steps about 5 min. About 35 minutes in all; mixer-cvae
# and mixer-cvae-dlow add 21 + 8 min (2026-11-27). (mixer-dct, retired on 2026-11-27, was trained
# here until then; its command is in its card in git history, commit 696e72f.) Logs and evaluation JSON go
# to out/train_shipped/; the periodic checkpoints (*.last*.safetensors) are removed once a model is done.
# Last, the mixtures are composed (nothing trained, seconds): mixture-dlow from the two DLow samplers, and
# mixture-periodic (the best sampler) from them and the mirror-periodic and settle rules; their cards,
# motion2video/weights/mixture-*.md, are written by hand from the evaluations printed to their logs.
# Afterwards: python scripts/make_results.py per-action, corpus and known-answer (their tables of docs/results.md).
#
# --bandai:
#   Train the samplers of mixture-periodic on the joined corpus (../shared/data/mocap + ../shared/data/bandai)
#   into motion2video/weights/*-bandai.safetensors, and compose mixture-periodic-bandai from them.
#
#     scripts/train_shipped.sh --bandai                  # all five, two lanes (one torch thread each)
#     STEPS_SCALE=0.1 scripts/train_shipped.sh --bandai  # a quick smoke run (10% of the steps)
#     ONLY="mtvae-add-bandai" scripts/train_shipped.sh --bandai
#     BASE_MINUTES=24 DLOW_MINUTES=10 scripts/train_shipped.sh --bandai   # wall-time budgets (a loaded machine)
#
#   The recipes are those of the default run (mtvae-add, mtvae-add-dlow, mixer-cvae, mixer-cvae-dlow),
#   with the subject split (held_out "subjects", docs/data.md): training never sees the corpus's test subjects nor
#   Bandai-Namco's skeleton groups 1B and 2C, so `evaluate --split subjects` and the corpus's test split both
#   score these models on people they never saw. Bandai-Namco's files are CC BY-NC 4.0: every checkpoint written
#   here is for non-commercial use (its card and its licence record say so).
#   BASE_MINUTES / DLOW_MINUTES (0: none) give the base models and the DLow samplers a wall-time budget per run
#   (TrainConfig.max_minutes: the learning rate follows whichever of steps and time is further along, and the run
#   ends annealed when the budget is spent; the checkpoint and its card record the steps done). The shipped *-bandai
#   checkpoints were trained without budgets, to the full recipes: 45 minutes for all four on the shared 2-core
#   machine (2026-11-29, other jobs running beside them).
#   Logs go to out/train_bandai/; the model cards are written by `scripts/make_results.py bandai --cards` from the
#   evaluations it runs (docs/results_bandai.md), then scripts/shipped_licences.py adds their data licences.
set -euo pipefail
cd "$(dirname "$0")/.."

# Settings both runs share (each may be overridden from the environment).
PY=${PY:-.venv/bin/python}
MOCAP=${MOCAP:-../shared/data/mocap}
WEIGHTS=${WEIGHTS:-motion2video/weights}
STEPS_SCALE=${STEPS_SCALE:-1}
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

steps() { "$PY" -c "import sys; print(max(1, round($1 * float(sys.argv[1]))))" "$STEPS_SCALE"; }

# The --bandai run: the samplers of mixture-periodic retrained on the joined corpus (header above).
train_bandai() {
  BANDAI=${BANDAI:-../shared/data/bandai}
  LOGS=${LOGS:-out/train_bandai}
  ONLY=${ONLY:-"mtvae-add-bandai mtvae-add-dlow-bandai mixer-cvae-bandai mixer-cvae-dlow-bandai mixture-periodic-bandai"}
  mkdir -p "$WEIGHTS" "$LOGS"

  BASE_MINUTES=${BASE_MINUTES:-0}
  DLOW_MINUTES=${DLOW_MINUTES:-0}
  DATA_SUBJECTS='"data": {"held_out": "subjects"}'
  MTVAE_BODY='"model": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128, "motion_stats_weight": 100.0}'
  TRAIN='"train": {"batch_size": 64, "lr": 0.001, "checkpoint_every": 500, "val_every": 500, "max_minutes": '$BASE_MINUTES'}'
  MIXER_CVAE='"model": {"kl_weight": 0.01, "stats_weight": 1.0}, "data": {"held_out": "subjects"}, "train": {"batch_size": 64, "lr": 0.002, "checkpoint_every": 1000, "val_every": 1000, "max_minutes": '$BASE_MINUTES'}'
  # DLow reuses its base checkpoint's data settings and split (apps/train.py), so it has no data section.
  DLOW='"model": {"num_samples": 50}, "train": {"batch_size": 16, "lr": 0.0005, "checkpoint_every": 200, "val_every": 200, "augment": true, "max_minutes": '$DLOW_MINUTES'}'


  # bandai_train_one NAME MODEL STEPS CONFIG [EXTRA ARGS...]
  bandai_train_one() {
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

  bandai_lane_a() {
    bandai_train_one mtvae-add-bandai mtvae-add 4000 "{$MTVAE_BODY, $DATA_SUBJECTS, $TRAIN}"
    bandai_train_one mtvae-add-dlow-bandai dlow 600 "{$DLOW}" --base "$WEIGHTS/mtvae-add-bandai.safetensors"
  }

  bandai_lane_b() {
    bandai_train_one mixer-cvae-bandai mixer-cvae 6000 "{$MIXER_CVAE}"
    bandai_train_one mixer-cvae-dlow-bandai dlow 600 "{$DLOW}" --base "$WEIGHTS/mixer-cvae-bandai.safetensors"
  }

  start=$SECONDS
  bandai_lane_a & a=$!
  bandai_lane_b & b=$!
  status=0
  wait $a || status=1
  wait $b || status=1
  case " $ONLY " in *" mixture-periodic-bandai "*)
    if [ $status -eq 0 ]; then
      "$PY" scripts/make_mixture.py "$WEIGHTS/mtvae-add-dlow-bandai.safetensors" "$WEIGHTS/mixer-cvae-dlow-bandai.safetensors" \
          mirror-periodic settle --shares 17,17,12,4 -o "$WEIGHTS/mixture-periodic-bandai.safetensors" \
          > "$LOGS/mixture-periodic-bandai.log" 2>&1 || status=1
      echo "[$(date +%T)] mixture-periodic-bandai composed (status $status)"
    fi ;;
  esac
  echo "all done in $(( (SECONDS - start) / 60 )) min (status $status); logs in $LOGS"
  exit $status
}

case "${1:-}" in
  --bandai) train_bandai; exit $? ;;
  "") ;;
  *) echo "usage: scripts/train_shipped.sh [--bandai]" >&2; exit 2 ;;
esac


FACE=${FACE:-../shared/data/face}
LOGS=${LOGS:-out/train_shipped}
ONLY=${ONLY:-"mtvae-add mtvae-add-dlow mtvae-add-2d mtvae-add-face lcpvae behavior mixer-cvae mixer-cvae-dlow mixture-dlow mixture-periodic"}
mkdir -p "$WEIGHTS" "$LOGS"

# Every body model learns from the whole corpus of ../shared/data/mocap (all 275 files, duplicates
# dropped) with the pinned subject-disjoint split (docs/data.md): test = CMU subjects 2/5/6/7 + benchmark
# walking, 131, 140, 94 (Indian dance); validation = 3, 85, benchmark basketball, MASS.
BODY_DATA='"data": {"held_out": "corpus"}'
MTVAE='"model": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128}'
# The body models add a liveliness term (motion_stats_weight: generated vs true mean |velocity| and
# |acceleration| per feature); without it their futures moved at 0.2-0.5x the speed of real motion.
MTVAE_BODY='"model": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128, "motion_stats_weight": 100.0}'
TRAIN='"train": {"batch_size": 64, "lr": 0.001, "checkpoint_every": 500, "val_every": 500}'
# LCP-VAE: a wide learned prior (cs_kl_weight, see models/lcpvae.py) and a short teacher-forcing phase
# (sampling decodes free-running; a long teacher-forced phase left the validation loss 8x above training).
LCP='"model": {"hidden_dim": 128, "latent_dim": 32, "mlp_dim": 128, "cs_kl_weight": 4.0, "teacher_forcing_steps": 300, "motion_stats_weight": 60.0}'
# mixer-cvae (models/mixer_cvae.py): a CVAE whose decoder is the DCT + MLP-mixer of models/mixer.py, KL weight 0.01,
# a liveliness term on prior samples; 21 min on one thread beside another run (2026-11-27). DLow samples it.
MIXER_CVAE='"model": {"kl_weight": 0.01, "stats_weight": 1.0}, "data": {"held_out": "corpus"}, "train": {"batch_size": 64, "lr": 0.002, "checkpoint_every": 1000, "val_every": 1000}'
# DLow on top of the trained mtvae-add: K = 50 affine maps of one noise, the base model frozen.
DLOW='"model": {"num_samples": 50}, "train": {"batch_size": 16, "lr": 0.0005, "checkpoint_every": 200, "val_every": 200, "augment": true}'


# train_one NAME MODEL DATA STEPS CONFIG [EXTRA ARGS...]
train_one() {
  local name=$1 model=$2 data=$3 n; n=$(steps "$4"); local config=$5; shift 5
  case " $ONLY " in *" $name "*) ;; *) return 0 ;; esac
  local out="$WEIGHTS/$name.safetensors"
  local cmd="motion2video train --model $model --data $data -o $out --steps $n --seed 0 --config '$config' $*"
  echo "[$(date +%T)] $name: $cmd"
  local t0=$SECONDS
  "$PY" -m motion2video.cli train --model "$model" --data "$data" -o "$out" --steps "$n" --seed 0 \
      --config "$config" --no-progress "$@" > "$LOGS/$name.log" 2>&1
  "$PY" -m motion2video.cli evaluate --model "$out" --data "$data" --samples 50 \
      --json "$LOGS/$name.eval.json" >> "$LOGS/$name.log" 2>&1
  "$PY" scripts/make_results.py card --checkpoint "$out" --eval "$LOGS/$name.eval.json" --command "$cmd" \
      --out "$WEIGHTS/$name.md" >> "$LOGS/$name.log" 2>&1
  rm -f "$WEIGHTS/$name.last.safetensors" "$WEIGHTS/$name.last.optim.safetensors"
  echo "[$(date +%T)] $name done in $((SECONDS - t0)) s ($(du -h "$out" | cut -f1))"
}

lane_a() {
  train_one mtvae-add mtvae-add "$MOCAP" 4000 "{$MTVAE_BODY, $BODY_DATA, $TRAIN}"
  train_one mtvae-add-dlow dlow "$MOCAP" 600 "{$DLOW}" --base "$WEIGHTS/mtvae-add.safetensors"
  # behaviour model with root-trajectory access (see weights/behavior.md): 4000 steps, 10-13 min
  train_one behavior behavior "$MOCAP" 4000 \
      "{\"model\": {\"hidden_dim\": 128, \"latent_dim\": 32, \"regressor_dim\": 128, \"decoder_feeds_z\": true, \"encoder_velocities\": true, \"kl_budget\": 100.0, \"root_weight\": 10.0, \"root_trajectory\": true, \"motion_stats_weight\": 60.0}, $BODY_DATA, $TRAIN}"
}

lane_b() {
  train_one lcpvae lcpvae "$MOCAP" 3000 "{$LCP, $BODY_DATA, $TRAIN}"
  train_one mtvae-add-2d mtvae-add "$MOCAP" 2500 "{$MTVAE_BODY, $BODY_DATA, $TRAIN}" --layout body2d
  train_one mtvae-add-face mtvae-add "$FACE" 1200 "{$MTVAE, $TRAIN}" --layout face
  train_one mixer-cvae mixer-cvae "$MOCAP" 6000 "{$MIXER_CVAE}"
  train_one mixer-cvae-dlow dlow "$MOCAP" 600 "{$DLOW}" --base "$WEIGHTS/mixer-cvae.safetensors"
}

start=$SECONDS
lane_a & a=$!
lane_b & b=$!
status=0
wait $a || status=1
wait $b || status=1
case " $ONLY " in *" mixture-dlow "*)
  if [ $status -eq 0 ]; then
    "$PY" scripts/make_mixture.py "$WEIGHTS/mtvae-add-dlow.safetensors" "$WEIGHTS/mixer-cvae-dlow.safetensors" \
        -o "$WEIGHTS/mixture-dlow.safetensors" > "$LOGS/mixture-dlow.log" 2>&1 || status=1
    "$PY" -m motion2video.cli evaluate --model "$WEIGHTS/mixture-dlow.safetensors" \
        --model "$WEIGHTS/mtvae-add-dlow.safetensors" --model "$WEIGHTS/mixer-cvae-dlow.safetensors" --data "$MOCAP" \
        --samples 50 --json "$LOGS/mixture-dlow.eval.json" >> "$LOGS/mixture-dlow.log" 2>&1 || status=1
    echo "[$(date +%T)] mixture-dlow composed (status $status)"
  fi ;;
esac
case " $ONLY " in *" mixture-periodic "*)
  if [ $status -eq 0 ]; then
    "$PY" scripts/make_mixture.py "$WEIGHTS/mtvae-add-dlow.safetensors" "$WEIGHTS/mixer-cvae-dlow.safetensors" \
        mirror-periodic settle --shares 17,17,12,4 -o "$WEIGHTS/mixture-periodic.safetensors" > "$LOGS/mixture-periodic.log" 2>&1 || status=1
    "$PY" -m motion2video.cli evaluate --model "$WEIGHTS/mixture-periodic.safetensors" \
        --model "$WEIGHTS/mixture-dlow.safetensors" --data "$MOCAP" \
        --samples 50 --json "$LOGS/mixture-periodic.eval.json" >> "$LOGS/mixture-periodic.log" 2>&1 || status=1
    echo "[$(date +%T)] mixture-periodic composed (status $status)"
  fi ;;
esac
echo "all done in $(( (SECONDS - start) / 60 )) min (status $status); logs in $LOGS"
exit $status
