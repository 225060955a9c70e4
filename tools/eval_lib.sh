# Shared by the evaluation scripts (sourced after `set -euo pipefail`): option parsing, the CPU
# load note and the binary snapshot, so every report states its run the same way.

# Sets DRY=1 for --dry-run; --help prints the calling script's header comment ($1 = the script).
parse_eval_args() {
    local script=$1
    shift
    DRY=0
    for a in "$@"; do
        case $a in
            --dry-run) DRY=1 ;;
            -h|--help) awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$script"; exit 0 ;;
            *) echo "unknown argument $a (see --help)" >&2; exit 2 ;;
        esac
    done
}

# Other CPU users now (reports print it: timings depend on them). Counts training processes
# whatever the binary is called (a copy such as /tmp/dancegen-train too).
load_note() {
    echo "$(pgrep -c -f 'dancegen[^ ]* train ' || true) \`dancegen train\` processes running at the start, load average $(cut -d' ' -f1-3 /proc/loadavg)"
}

# Hard-links (or copies) binary $1 to $2/bin/dancegen, so a rebuild during the run cannot swap it
# midway; sets BIN.
snapshot_binary() {
    mkdir -p "$2/bin"
    BIN=$2/bin/dancegen
    ln -f "$1" "$BIN" 2>/dev/null || cp -f "$1" "$BIN"
}
