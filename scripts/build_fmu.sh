#!/usr/bin/env bash
# Builds the release library and writes the FMUs of both models from it:
#   target/fmu/StackedLiveLoad.fmu        FMI 2.0 Co-Simulation (the stack on an SDOF storey)
#   target/fmu/fmi3/StackedLiveLoad.fmu   FMI 3.0 Co-Simulation (early return, Event Mode)
#   target/fmu/StackOnFloor.fmu           FMI 2.0 (the stack on another model's floor)
#   target/fmu/fmi3/StackOnFloor.fmu      FMI 3.0
# (one library, copied into each FMU under the FMU's model identifier; the
# GUID / instantiation token picks the model),
# each with modelDescription.xml, documentation/, resources/default_record.csv
# (the embedded default ground motion) and the binaries of every platform built:
#   x86-64 Linux  (FMI 2.0 binaries/linux64,  FMI 3.0 binaries/x86_64-linux), always;
#   x86-64 Windows (win64, x86_64-windows) and aarch64 Linux (aarch64-linux, both),
#   cross-built when their Rust target and C linker are installed (scripts/setup.sh
#   installs them); SLL_CROSS=0 turns the cross builds off. A platform left out
#   is named on stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --lib --bin model_description

# Cross builds: (Rust target, C linker, FMI 2.0 folder, FMI 3.0 folder, library file).
cross=(
  "x86_64-pc-windows-gnu x86_64-w64-mingw32-gcc win64 x86_64-windows stacked_live_load.dll"
  "aarch64-unknown-linux-gnu aarch64-linux-gnu-gcc aarch64-linux aarch64-linux libstacked_live_load.so"
)
built=("target/release/libstacked_live_load.so linux64 x86_64-linux")
if [ "${SLL_CROSS:-1}" != 0 ]; then
  installed=$(rustup target list --installed 2>/dev/null || true)
  for row in "${cross[@]}"; do
    read -r triple linker fmi2dir fmi3dir lib <<<"$row"
    if ! grep -qx "$triple" <<<"$installed" || ! command -v "$linker" >/dev/null; then
      echo "build_fmu: $triple left out (needs 'rustup target add $triple' and $linker: scripts/setup.sh)" >&2
      continue
    fi
    env_name="CARGO_TARGET_$(tr 'a-z-' 'A-Z_' <<<"$triple")_LINKER"
    if ! env "$env_name=$linker" cargo build --quiet --release --lib --target "$triple"; then
      echo "build_fmu: $triple left out: its cross build failed (above)" >&2
      continue
    fi
    built+=("target/$triple/release/$lib $fmi2dir $fmi3dir")
  done
fi

package() {  # package VERSION MODEL OUT
  local version=$1 model=$2 out=$3 stage=target/fmu/stage$1$2
  rm -rf "$stage"
  mkdir -p "$stage/documentation" "$stage/resources" "$(dirname "$out")"
  local folder=modelDescription
  [ "$model" = StackedLiveLoad ] || folder=modelDescription/$model
  local committed=$folder/modelDescription.xml
  [ "$version" = 3 ] && committed=$folder/fmi3/modelDescription.xml
  ./target/release/model_description "$version" "$model" > "$stage/modelDescription.xml"
  cmp -s "$stage/modelDescription.xml" "$committed" || {
    echo "$committed is stale: regenerate it with" >&2
    echo "  UPDATE_GENERATED=1 cargo test --test generated_files" >&2
    exit 1
  }
  for row in "${built[@]}"; do
    read -r lib fmi2dir fmi3dir <<<"$row"
    local dir=$fmi2dir ext=${lib##*.}
    [ "$version" = 3 ] && dir=$fmi3dir
    mkdir -p "$stage/binaries/$dir"
    cp "$lib" "$stage/binaries/$dir/$model.$ext"
  done
  cp README.md "$stage/documentation/README.md"
  cp -r docs "$stage/documentation/docs"   # the README links into docs/
  cp resources/default_record.csv "$stage/resources/default_record.csv"
  printf '<html><body><p>See <a href="README.md">README.md</a>.</p></body></html>\n' > "$stage/documentation/index.html"
  python3 - "$stage" "$out" <<'PY'
import os, sys, zipfile
stage, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
    for root, dirs, files in os.walk(stage):
        dirs.sort()
        for name in sorted(files):
            path = os.path.join(root, name)
            z.write(path, os.path.relpath(path, stage))
        if not files and not dirs:  # keep empty folders
            z.writestr(os.path.relpath(root, stage) + "/", "")
print(out)
PY
}
package 2 StackedLiveLoad target/fmu/StackedLiveLoad.fmu
package 3 StackedLiveLoad target/fmu/fmi3/StackedLiveLoad.fmu
package 2 StackOnFloor target/fmu/StackOnFloor.fmu
package 3 StackOnFloor target/fmu/fmi3/StackOnFloor.fmu
