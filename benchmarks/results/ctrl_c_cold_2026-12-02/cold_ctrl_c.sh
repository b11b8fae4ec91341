#!/bin/bash
# Ctrl-C into a cold CLI simulate (three disks, empty cache), at several delays.
# SIGINT starts at its default (dfl.py): a background job of a non-interactive shell
# inherits it ignored. Usage: [PYTHONPATH=TREE] bash cold_ctrl_c.sh > out.txt
here=$(cd "$(dirname "$0")" && pwd)
cd /tmp
for d in ${DELAYS:-5 6 7 8 8 9 10 11 12 14}; do
  c=$(mktemp -d)
  NUMBA_CACHE_DIR=$c python3 "$here/dfl.py" python3 -m stickslip_fast.cli simulate --preset literature --eta 2.7 --n-oscillators 3 --drive dc-motor --max-points 10 --t-end 1e8 > $c/out 2> $c/err &
  pid=$!
  sleep $d
  kill -INT $pid
  wait $pid
  rc=$?
  echo "delay $d rc $rc last: $(tail -1 $c/err) | RuntimeError: $(grep -c RuntimeError $c/err) KeyboardInterrupt: $(grep -c KeyboardInterrupt $c/err) ignored: $(grep -c 'Exception ignored' $c/err)"
  rm -rf $c
done
