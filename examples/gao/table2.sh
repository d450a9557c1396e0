#!/bin/sh
# Gao Table 2 beside this engine (docs/gao-table2.md): each scene run with mpm run --threads 2;
# prints steps, particles (first -> last frame), wall seconds, ms per step and max RSS.
# Run from anywhere after make build; outputs under /tmp/m_NAME.
cd "$(dirname "$0")/../.."
run() { # name scene end
  python3 -c "
import json,sys,os;s=json.load(open('$2'))
if '$3': s['time']['end']=float('$3')
for b in s['bodies']:
  f=b['shape'].get('file')
  if f and not os.path.isabs(f): b['shape']['file']=os.path.abspath(os.path.join(os.path.dirname('$2'),f))
json.dump(s,open('/tmp/m_$1.json','w'))"
  /usr/bin/time -f "%M" -o /tmp/m_$1.rss ./build/mpm run /tmp/m_$1.json -o /tmp/m_$1 --threads 2 --overwrite > /tmp/m_$1.log 2>&1
  awk -F, -v n=$1 -v rss=$(cat /tmp/m_$1.rss) 'NR==1{for(i=1;i<=NF;i++)h[$i]=i} NR>1{s+=$h["wall_seconds"]; st=$h["steps"]; p=$h["particles"]; if(NR==2)p0=$h["particles"]} END{printf "%s steps %d particles %d -> %d wall %.1f s ms/step %.2f rss %.0f MB\n", n, st, p0, p, s, 1000*s/st, rss/1024}' /tmp/m_$1/stats.csv
  grep -E "refinement:|resampling:" /tmp/m_$1.log
}
run hg_uniform examples/gao/hourglass_uniform.json 0.5
run hg_adaptive examples/gao/hourglass_adaptive.json 0.5
run jello_fine examples/gao/jello_collision_fine.json ""
run jello_static examples/gao/jello_collision_adaptive.json ""
run jello_dynamic examples/gao/jello_collision_dynamic.json ""
run slits_fine examples/goo_slits.json ""
run slits_adaptive examples/gao/goo_slits_adaptive.json ""
run slits_resample examples/gao/goo_slits_resample.json ""
run drum_off examples/gao/sand_drum_resample_off.json 1.5
run drum_on examples/gao/sand_drum_resample_on.json 1.5
for n in slits_fine slits_adaptive slits_resample; do /usr/bin/python3 examples/gao/mass_below.py /tmp/m_$n 0.28 | tail -1; done
/usr/bin/python3 examples/gao/closest_approach.py /tmp/m_jello_fine | tail -1
/usr/bin/python3 examples/gao/closest_approach.py /tmp/m_jello_dynamic | tail -1
