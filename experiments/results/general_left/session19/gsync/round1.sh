# Four GPUs: GSync (planner v11, plans carried) on spring_overture and johnny_b_goodie; snow at matmul precision
# "highest"; snow against a quieter frozen left hand (std 3e-4); beside them, the left hand's precision check.
mkdir -p /tmp/plans /tmp/official /tmp/runs/gsync && cp $REPO/.data/plans/*.npz /tmp/plans/ \
  && cp $REPO/.data/official/*.json /tmp/official/ && cp -r $REPO/.data/left_quiet /tmp/left_quiet
export DEXGUITAR_PLANS=/tmp/plans
one() { g=$1; n=$2; s=$3; shift 3; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config experiments/sync_songs.py --max-minutes ${MIN:-8} "$@" > /tmp/runs/gsync/$n.log 2>&1
  echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 spring_overture spring_overture &
one 1 johnny_b_goodie johnny_b_goodie &
JAX_DEFAULT_MATMUL_PRECISION=highest one 2 snow_highest snow &
one 3 snow_quiet snow --left /tmp/left_quiet --right /tmp/code/models/policies/right_mixed &
sleep 150; GPU=2 bash $REPO/.data/prec.sh > /tmp/runs/prec.log 2>&1 &
wait
echo "gsync done"
