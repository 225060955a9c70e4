#!/usr/bin/env bash
# Contact sheet of dance motions: draws every motion at the same frames with `dancegen render`
# and lays the pictures out as a grid, one row per motion, one column per frame, each picture
# labelled "LABEL, T s (frame N)". The evaluation scripts use it to show generated and real
# motion side by side (floating feet, odd poses).
#
#   bash tools/contact_sheet.sh OUT.png FRAMES LABEL=MOTION [LABEL=MOTION ...]
#
#   OUT.png       the sheet (made under a temporary name, then moved into place)
#   FRAMES        frame indices, separated by spaces or commas ("60 150 240"), counted at each
#                 motion's own frame rate (`dancegen render --frame`)
#   LABEL=MOTION  one row: its label and a motion file `dancegen render` reads (joints .npy
#                 (T, 24, 3), SMPL .npz, .bvh, ...); files joined by "+" are drawn together in
#                 one picture (a couple: LABEL=leader.npy+follower.npy)
#
# `dancegen render` draws a joints .npy as loose spheres (it has no skeleton). So that every row
# shows a stick figure, each SMPL 24 joints .npy (T, 24, 3) is first written as a BVH with the
# SMPL 24 hierarchy whose joints carry position channels only (each joint's offset from its
# parent, frame by frame, frame time 1/FPS): the same positions, drawn with bones.
#
# Environment (all optional):
#   DANCEGEN=target/release/dancegen
#   FPS=30               frame rate of joints .npy files (their BVH frame time) and of the
#                        seconds in the labels
#   WORK=DIR             where the single pictures and BVH files go (default: a temporary
#                        directory, removed at the end; a given WORK is kept)
#   WIDTH=400 HEIGHT=300 size of each picture
#   FONT=DejaVu-Sans     ImageMagick font of the labels (ImageMagick's default if missing)
#   PYTHON=python3       (standard library only) for the .npy -> BVH step
#
# Example: bash tools/contact_sheet.sh sheet.png "60 150 240" generated=gen.npy real=real.npy
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ $# -lt 3 ]; then
    awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$0" >&2
    exit 2
fi
OUT_PNG=$1
FRAMES=$2
shift 2
DANCEGEN=${DANCEGEN:-$ROOT/target/release/dancegen}
FPS=${FPS:-30}
WIDTH=${WIDTH:-400}
HEIGHT=${HEIGHT:-300}
FONT=${FONT:-DejaVu-Sans}
PYTHON=${PYTHON:-python3}

[ -x "$DANCEGEN" ] || { echo "contact_sheet: $DANCEGEN is not an executable (set DANCEGEN)" >&2; exit 1; }
if command -v montage >/dev/null; then MONTAGE=(montage)
elif command -v magick >/dev/null; then MONTAGE=(magick montage)
else echo "contact_sheet: ImageMagick's montage not found" >&2; exit 1; fi
FONT_ARGS=()
if convert -list font 2>/dev/null | grep -q "Font: $FONT\$"; then FONT_ARGS=(-font "$FONT"); fi

read -r -a frames <<< "${FRAMES//,/ }"
[ "${#frames[@]}" -gt 0 ] || { echo "contact_sheet: no frames given" >&2; exit 2; }
for f in "${frames[@]}"; do
    [[ $f =~ ^[0-9]+$ ]] || { echo "contact_sheet: frame '$f' is not a non-negative integer" >&2; exit 2; }
done

if [ -n "${WORK:-}" ]; then
    mkdir -p "$WORK"
else
    WORK=$(mktemp -d)
    trap 'rm -rf "$WORK"' EXIT
fi

# ImageMagick reads a label starting with "@" as a file name and expands "%" escapes.
escape_label() {
    local s=${1//%/%%}
    [ "${s:0:1}" = "@" ] && s="\\$s"
    printf '%s' "$s"
}

# A (T, 24, 3) joints .npy as a BVH with the SMPL 24 hierarchy and position channels only (see
# above): prints the BVH's path, or the input's for any other file.
with_bones() { # file index
    case $1 in *.npy) ;; *) echo "$1"; return ;; esac
    "$PYTHON" - "$1" "$WORK/motion$2.bvh" "$FPS" <<'PY'
import ast, struct, sys
from array import array

src, dst, fps = sys.argv[1], sys.argv[2], float(sys.argv[3])
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
with open(src, "rb") as f:
    magic, major = f.read(6), f.read(2)[0]
    hlen = struct.unpack("<H" if major == 1 else "<I", f.read(2 if major == 1 else 4))[0]
    header = ast.literal_eval(f.read(hlen).decode("latin1"))
    code = {"<f4": "f", "<f8": "d"}.get(header["descr"])
    shape = tuple(header["shape"])
    if magic != b"\x93NUMPY" or code is None or header.get("fortran_order") \
            or len(shape) != 3 or shape[1:] != (24, 3):
        print(src)  # not SMPL 24 joints: drawn as it is
        sys.exit(0)
    a = array(code)
    a.frombytes(f.read())
if sys.byteorder != "little":
    a.byteswap()
kids = [[k for k in range(24) if PARENTS[k] == j] for j in range(24)]
lines, order = ["HIERARCHY"], []


def joint(j, depth):
    ind = "  " * depth
    order.append(j)
    lines.extend([f"{ind}{'ROOT' if j == 0 else 'JOINT'} joint{j}", ind + "{",
                  f"{ind}  OFFSET 0 0 0", f"{ind}  CHANNELS 3 Xposition Yposition Zposition"])
    for k in kids[j]:
        joint(k, depth + 1)
    if not kids[j]:
        lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET 0 0 0", f"{ind}  }}"])
    lines.append(ind + "}")


joint(0, 0)
frames = shape[0]
lines.extend(["MOTION", f"Frames: {frames}", f"Frame Time: {1.0 / fps:.9f}"])
for t in range(frames):
    row = []
    for j in order:
        b, p = (t * 24 + j) * 3, (t * 24 + PARENTS[j]) * 3
        row.extend(f"{a[b + i] - (a[p + i] if j else 0.0):.5f}" for i in range(3))
    lines.append(" ".join(row))
with open(dst, "w") as f:
    f.write("\n".join(lines) + "\n")
print(dst)
PY
}

tiles=()
longest=0
row=0
n_file=0
for spec in "$@"; do
    case $spec in
        *=?*) ;;
        *) echo "contact_sheet: '$spec' is not LABEL=MOTION" >&2; exit 2 ;;
    esac
    label=${spec%%=*}
    IFS='+' read -r -a files <<< "${spec#*=}"
    drawn=()
    for m in "${files[@]}"; do
        [ -f "$m" ] || { echo "contact_sheet: $m: no such file" >&2; exit 1; }
        drawn+=("$(with_bones "$m" "$n_file")")
        n_file=$((n_file + 1))
    done
    col=0
    for f in "${frames[@]}"; do
        tile=$WORK/r${row}_c${col}.png
        "$DANCEGEN" -q render "${drawn[@]}" -o "$tile" --frame "$f" --width "$WIDTH" \
            --height "$HEIGHT"
        secs=$(awk -v f="$f" -v r="$FPS" 'BEGIN{printf "%.1f", f / r}')
        text="$label, $secs s (frame $f)"
        [ "${#text}" -gt "$longest" ] && longest=${#text}
        tiles+=(-label "$(escape_label "$text")" "$tile")
        col=$((col + 1))
    done
    row=$((row + 1))
done

# Labels are drawn at 15 pt unless the longest would be wider than its picture (a DejaVu Sans
# character is about 0.56 em wide): then smaller, down to 9 pt, so neighbours do not overlap.
pointsize=$(awk -v w="$WIDTH" -v n="$longest" 'BEGIN{p = 15; if (n > 0 && w / (0.56 * n) < p) p = int(w / (0.56 * n)); if (p < 9) p = 9; print p}')
mkdir -p "$(dirname "$OUT_PNG")"
part=${OUT_PNG%.*}.part$$.png
"${MONTAGE[@]}" "${FONT_ARGS[@]}" -pointsize "$pointsize" -background white "${tiles[@]}" \
    -tile "${#frames[@]}x$row" -geometry "${WIDTH}x${HEIGHT}+4+4" "$part" \
    || { rm -f "$part"; echo "contact_sheet: montage failed" >&2; exit 1; }
mv -f "$part" "$OUT_PNG"
echo "wrote $OUT_PNG ($row rows x ${#frames[@]} columns)" >&2
