#!/usr/bin/env bash
# Seed corpora of the fuzz targets (fuzz/corpus/<target>, not committed): the MSH fixtures of
# tests/fixtures, the shipped geo/*.geo scripts meshed coarsely by gmsh (ascii and binary),
# and the case files of pipelines/ and tests/.
set -euo pipefail
cd "$(dirname "$0")/.."
out=fuzz/corpus
mkdir -p "$out/msh_reader" "$out/model_build" "$out/case_file" build/fuzz-seed
for f in tests/fixtures/*.msh; do cp "$f" "$out/msh_reader/"; done
for geo in geo/*.geo tests/fixtures/*.geo; do
  name=$(basename "$geo" .geo)
  for format in ascii bin; do
    flag=$([ $format = bin ] && echo -bin || true)
    msh=build/fuzz-seed/$name-$format.msh
    [ -f "$msh" ] || timeout 60 gmsh "$geo" -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1 \
      -format msh41 $flag -clscale 4 -v 0 -o "$msh" >/dev/null 2>&1 || continue
    # Keep seeds small: the fuzzer mutates faster and finds more on small inputs.
    [ "$(stat -c %s "$msh")" -le 200000 ] && cp "$msh" "$out/msh_reader/"
  done
done
# model_build: one byte (analysis, contact recipe) before the mesh.
for f in "$out"/msh_reader/*.msh; do
  for mode in 0 3 4; do
    { printf "\\$(printf '%03o' $mode)"; cat "$f"; } > "$out/model_build/$mode-$(basename "$f")"
  done
done
# case_file: mode byte 0 = raw text.
find pipelines tests -name '*.toml' | while read -r f; do
  { printf '\000'; cat "$f"; } > "$out/case_file/$(echo "$f" | tr / _)"
done
echo "seeds: $(ls "$out/msh_reader" | wc -l) meshes, $(ls "$out/case_file" | wc -l) cases"
