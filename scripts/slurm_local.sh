#!/usr/bin/env bash
# The protocol workflow through workflow/profiles/slurm on a real Slurm: starts a one-node cluster on this machine
# (Debian's slurm-wlm: slurmctld + slurmd on localhost, munge for authentication, no accounting database), runs a
# small subset of the protocol (workflow/subset_small.yaml: 2 cells, 3 runs, rendered 5 s flights) through the
# Slurm profile and again through the local profile, and checks that the records agree: every trajectory byte for byte
# and every field of every JSON record except the wall-clock timings. Stops what it started. docs/slurm.md.
# Needs root (daemons, apt) and ../shared/data/euroc_groundtruth. Usage: scripts/slurm_local.sh [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
WORK=$(realpath -m "${1:-$(mktemp -d)}")
mkdir -p "$WORK"
[ -x build/ovton ] || {
  echo "slurm_local: build/ovton not found (scripts/build.sh first)"
  exit 2
}
[ -d ../shared/data/euroc_groundtruth ] || {
  echo "slurm_local: ../shared/data/euroc_groundtruth absent: the protocol renders along it"
  exit 2
}
scripts/install_deps.sh slurm-wlm munge snakemake python3
export USER=${USER:-$(id -un)} # Snakemake's Slurm executor reads it

PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do
    kill "$p" 2>/dev/null || true
  done
}
trap cleanup EXIT

# munge: one key, one daemon (kept if one already answers).
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  [ -s /etc/munge/munge.key ] || mungekey --create --keyfile=/etc/munge/munge.key
  chown munge:munge /etc/munge/munge.key
  chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  runuser -u munge -- /usr/sbin/munged --foreground >"$WORK/munged.log" 2>&1 &
  PIDS+=($!)
  for _ in $(seq 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break || sleep 0.2; done
fi
munge -n | unmunge >/dev/null || {
  echo "slurm_local: munged does not answer"
  exit 1
}

# slurm.conf: one node (this machine, as localhost), partition `batch` as the profile names it, cores and memory
# as scheduled resources, processes tracked without cgroups, no accounting (Snakemake falls back to scontrol).
CONF="$WORK/slurm"
mkdir -p "$CONF/state" "$CONF/spool"
CPUS=$(nproc)
MEM=$(($(awk '/MemTotal/{print $2}' /proc/meminfo) / 1024 - 1024))
cat >"$CONF/slurm.conf" <<EOF
ClusterName=ovton
SlurmctldHost=localhost
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$CONF/state
SlurmdSpoolDir=$CONF/spool
SlurmctldPidFile=$CONF/slurmctld.pid
SlurmdPidFile=$CONF/slurmd.pid
SlurmctldLogFile=$CONF/slurmctld.log
SlurmdLogFile=$CONF/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
NodeName=localhost CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=batch Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$CONF/slurm.conf"
/usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$CONF/slurmctld.out" 2>&1 &
PIDS+=($!)
/usr/sbin/slurmd -D -f "$SLURM_CONF" >"$CONF/slurmd.out" 2>&1 &
PIDS+=($!)
up=""
for _ in $(seq 60); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qx idle; then
    up=yes
    break
  fi
  sleep 1
done
if [ -z "$up" ]; then
  echo "slurm_local: the node did not come up; sinfo says: $(sinfo 2>&1 | tail -2)"
  tail -5 "$CONF/slurmctld.log" "$CONF/slurmd.log" "$CONF"/*.out 2>/dev/null
  exit 1
fi
echo "slurm_local: one-node Slurm up: $(sinfo -h -o '%P %D %c %m %T')"

COMMON=(-s workflow/Snakefile --configfile workflow/config.yaml workflow/subset_small.yaml --quiet)
t0=$SECONDS
snakemake "${COMMON[@]}" --profile workflow/profiles/slurm --config out="$WORK/slurm_run" >"$WORK/slurm_run.log" 2>&1 || {
  echo "slurm_local: the Slurm run failed ($WORK/slurm_run.log):"
  tail -20 "$WORK/slurm_run.log"
  exit 1
}
t1=$SECONDS
jobs=$(grep -c 'has been submitted with SLURM jobid' "$WORK/slurm_run.log" || true)
snakemake "${COMMON[@]}" --profile workflow/profiles/local --config out="$WORK/local_run" >"$WORK/local_run.log" 2>&1
echo "slurm_local: Slurm profile $((t1 - t0)) s ($jobs jobs submitted), local profile $((SECONDS - t1)) s"

python3 - "$WORK/slurm_run" "$WORK/local_run" <<'PY'
import filecmp, glob, json, os, sys
a, b = sys.argv[1], sys.argv[2]
TIMING = {"wall_s", "load_ms", "tracking_ms", "propagation_ms", "update_ms", "realtime", "networks_ms"}
recs = sorted(p for p in glob.glob(f"{a}/runs/*/*.json") if not p.endswith("_eval.json"))
bad = 0
for p in recs:
    q = p.replace(a, b, 1)
    # The records name their own folders (dataset, and a failed run's message): compare them with the root taken out.
    ra = json.loads(open(p).read().replace(a, "OUT"))
    rb = json.loads(open(q).read().replace(b, "OUT"))
    diff = {k for k in set(ra) | set(rb) if k not in TIMING and ra.get(k) != rb.get(k)}
    same_traj = filecmp.cmp(p[:-5] + ".csv", q[:-5] + ".csv", shallow=False)
    bad += bool(diff) or not same_traj
    print(f"  {os.path.relpath(p, a)}: status {ra['status']}, APE {ra.get('ape_rmse_m')}, TPE {ra.get('tpe_rmse_mm')}"
          f" — {'same' if not diff and same_traj else 'DIFFERS: ' + ', '.join(sorted(diff)) + ('' if same_traj else ' trajectory')}")
if not recs:
    sys.exit("slurm_local: the Slurm run wrote no records")
if bad:
    sys.exit(f"slurm_local: {bad} of {len(recs)} records differ between the Slurm and the local profile")
print(f"slurm_local: {len(recs)} records, trajectories byte-identical and fields equal (timings aside) "
      "between the Slurm and the local profile")
PY
