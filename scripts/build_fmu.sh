#!/usr/bin/env bash
# Builds the release library and writes target/fmu/StackedLiveLoad.fmu:
# modelDescription.xml, binaries/linux64/StackedLiveLoad.so, documentation/,
# resources/default_record.csv (the embedded default ground motion).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --lib --bin model_description
stage=target/fmu/stage
rm -rf "$stage"
mkdir -p "$stage/binaries/linux64" "$stage/documentation" "$stage/resources"
./target/release/model_description > "$stage/modelDescription.xml"
cmp -s "$stage/modelDescription.xml" modelDescription/modelDescription.xml || {
  echo "modelDescription/modelDescription.xml is stale: regenerate it with" >&2
  echo "  cargo run --bin model_description > modelDescription/modelDescription.xml" >&2
  exit 1
}
cp target/release/libstacked_live_load.so "$stage/binaries/linux64/StackedLiveLoad.so"
cp README.md "$stage/documentation/README.md"
cp -r docs "$stage/documentation/docs"   # the README links into docs/
cp resources/default_record.csv "$stage/resources/default_record.csv"
printf '<html><body><p>See <a href="README.md">README.md</a>.</p></body></html>\n' > "$stage/documentation/index.html"
python3 - "$stage" target/fmu/StackedLiveLoad.fmu <<'PY'
import os, sys, zipfile
stage, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
    for root, dirs, files in os.walk(stage):
        dirs.sort()
        for name in sorted(files):
            path = os.path.join(root, name)
            z.write(path, os.path.relpath(path, stage))
        if not files and not dirs:  # keep empty folders (resources/)
            z.writestr(os.path.relpath(root, stage) + "/", "")
print(out)
PY
