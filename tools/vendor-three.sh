#!/usr/bin/env bash
# Vendors the pinned three.js files the web app (crates/dancegen-server/web/) imports, so the page
# needs no CDN, no bundler and nothing from the network at run time.
#
# Fetches the npm tarball with `npm pack` (the ordinary npm client), checks its SHA-256 against
# the pin below, and copies exactly the files the page imports plus what they import in turn:
#
#   build/three.module.js, build/three.core.js         -> web/vendor/three/
#   examples/jsm/loaders/GLTFLoader.js                 -> web/vendor/three/addons/loaders/
#   examples/jsm/utils/BufferGeometryUtils.js          -> web/vendor/three/addons/utils/
#   examples/jsm/utils/SkeletonUtils.js                -> web/vendor/three/addons/utils/
#   examples/jsm/controls/OrbitControls.js             -> web/vendor/three/addons/controls/
#   LICENSE                                            -> web/vendor/three/LICENSE
#
# and writes VERSION and README.md there. The page's import map points `three` at
# ./vendor/three/three.module.js and `three/addons/` at ./vendor/three/addons/ (the same layout
# as three's own `three/addons/` export). After copying, every relative import of every copied
# file is checked to resolve to a copied file, so an upgrade that adds a dependency fails here
# instead of in the browser.
#
# To upgrade: change VERSION, run once with EXPECTED_SHA256= (empty) to print the new hash,
# read the diff of the vendored files, then pin the new hash.
set -euo pipefail
cd "$(dirname "$0")/.."

VERSION=0.187.0
# sha256 of three-0.187.0.tgz as served by the npm registry (npm's own sha1 is face29ee2de9…).
EXPECTED_SHA256=${EXPECTED_SHA256-ff540832ded0cfe919764d24a3d88f3e2a05f23303f876423e4f893841e90728}
DEST=crates/dancegen-server/web/vendor/three

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

(cd "$tmp" && npm pack --silent "three@$VERSION" >/dev/null)
tarball="$tmp/three-$VERSION.tgz"
[ -f "$tarball" ] || { echo "vendor-three.sh: npm pack did not produce $tarball" >&2; exit 1; }
sha256=$(sha256sum "$tarball" | cut -d' ' -f1)
sha1=$(sha1sum "$tarball" | cut -d' ' -f1)
if [ -n "$EXPECTED_SHA256" ] && [ "$sha256" != "$EXPECTED_SHA256" ]; then
  echo "vendor-three.sh: three-$VERSION.tgz has sha256 $sha256, expected $EXPECTED_SHA256" >&2
  exit 1
fi
tar -xzf "$tarball" -C "$tmp"
pkg="$tmp/package"

rm -rf "$DEST"
mkdir -p "$DEST/addons/loaders" "$DEST/addons/utils" "$DEST/addons/controls"
cp "$pkg/build/three.module.js" "$pkg/build/three.core.js" "$DEST/"
cp "$pkg/examples/jsm/loaders/GLTFLoader.js" "$DEST/addons/loaders/"
cp "$pkg/examples/jsm/utils/BufferGeometryUtils.js" "$pkg/examples/jsm/utils/SkeletonUtils.js" "$DEST/addons/utils/"
cp "$pkg/examples/jsm/controls/OrbitControls.js" "$DEST/addons/controls/"
cp "$pkg/LICENSE" "$DEST/LICENSE"

# Every static or dynamic import must be 'three' (the import map) or a relative path to a
# copied file.
status=0
while IFS= read -r -d '' f; do
  dir=$(dirname "$f")
  while IFS= read -r spec; do
    case "$spec" in
      three) ;;
      ./* | ../*)
        [ -f "$dir/$spec" ] || { echo "vendor-three.sh: $f imports $spec, which is not vendored" >&2; status=1; } ;;
      *) echo "vendor-three.sh: $f imports '$spec', which the import map does not provide" >&2; status=1 ;;
    esac
  done < <(grep -E "^\s*((import|export)\b.*|\})\s*from\s*'[^']+'|^\s*import\s*'[^']+'|\bimport\(\s*'[^']+'\s*\)" "$f" |
    grep -oE "'[^']+'\s*\)?\s*;?\s*$" | sed -E "s/^'([^']+)'.*/\1/" | sort -u)
done < <(find "$DEST" -name '*.js' -print0)
[ "$status" -eq 0 ] || exit 1

printf 'three %s\nnpm tarball three-%s.tgz sha256 %s sha1 %s\n' "$VERSION" "$VERSION" "$sha256" "$sha1" >"$DEST/VERSION"
cat >"$DEST/README.md" <<EOF
# three.js $VERSION (vendored)

Unmodified files from the npm package \`three@$VERSION\` (MIT, see \`LICENSE\`), copied by
\`tools/vendor-three.sh\`; do not edit them by hand, re-run the script.

- tarball \`three-$VERSION.tgz\`: sha256 \`$sha256\`, sha1 \`$sha1\`
- \`three.module.js\`, \`three.core.js\` from \`build/\`
- \`addons/\` from \`examples/jsm/\`: \`loaders/GLTFLoader.js\`, \`utils/BufferGeometryUtils.js\`,
  \`utils/SkeletonUtils.js\`, \`controls/OrbitControls.js\`

The page's import map: \`{"imports":{"three":"./vendor/three/three.module.js","three/addons/":"./vendor/three/addons/"}}\`.
EOF
echo "vendored three $VERSION (sha256 $sha256) into $DEST"
