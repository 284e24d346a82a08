# Left alone (left_general, zero residual) on five official songs on one GPU: JAX's default matmul precision, then
# the highest (float32 matmuls instead of TF32).
export DEXGUITAR_PLANS=/tmp/plans
S="snow turkish_march johnny_b_goodie beethoven_virus flight_of_the_bumblebee1"
for p in default highest; do
  CUDA_VISIBLE_DEVICES=${GPU:-3} JAX_DEFAULT_MATMUL_PRECISION=$p XLA_PYTHON_CLIENT_PREALLOCATE=false dexguitar eval --ckpt /tmp/code/models/policies/left_general \
    --song $(for s in $S; do echo /tmp/official/$s.json; done) > /tmp/runs/prec_$p.log 2>&1
  echo "precision $p rc=$?"; grep -h "F1" /tmp/runs/prec_$p.log | grep -v "^\s*chord" | cut -c1-120
done
