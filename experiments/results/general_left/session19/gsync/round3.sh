# Four GPUs, 6.5 min each: GSync on spring_overture and johnny_b_goodie with and without the hold reward
# (experiments/sync_hold.py vs sync_songs.py), the same code (env matmuls in float32), plans carried.
mkdir -p /tmp/plans /tmp/official /tmp/runs/gsync && cp $REPO/.data/plans/*.npz /tmp/plans/ \
  && cp $REPO/.data/official/*.json /tmp/official/
export DEXGUITAR_PLANS=/tmp/plans
one() { g=$1; n=$2; s=$3; c=$4; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config experiments/$c.py --max-minutes ${MIN:-6.5} > /tmp/runs/gsync/$n.log 2>&1
  echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 spring_hold spring_overture sync_hold &
one 1 spring_base spring_overture sync_songs &
one 2 johnny_hold johnny_b_goodie sync_hold &
one 3 johnny_base johnny_b_goodie sync_songs &
wait
echo "gsync done"
