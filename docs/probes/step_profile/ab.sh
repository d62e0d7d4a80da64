# interleaved A/B rounds, each version in its own process and numba cache
source /tmp/hR/.venv/bin/activate
R=$1; WHICH=$2; SC=$3
for r in $(seq 1 $R); do
  if [ $((r % 2)) -eq 1 ]; then L="old new"; else L="new old"; fi
  for v in $L; do
    NUMBA_CACHE_DIR=/tmp/hR_ab_numba_$v PYTHONPATH=/tmp/hR_$v python /tmp/hR_probe/tround.py $WHICH $SC $v 3
  done
done
