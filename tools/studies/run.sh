#!/bin/sh
# make studies: regenerates the tables of docs/STUDIES.md (between its <!-- studies:NAME -->
# and <!-- /studies:NAME --> markers) and docs/images/studies_*.png from scratch.
# Usage: tools/studies/run.sh [BUILD_DIR]; the 1024x512 HDRIs are the repository's copies in
# tests/data (IBL_TESTDATA=DIR reads DIR/hdri instead). One thread throughout.
set -eu
BUILD=${1:-build}
HDRI=${IBL_TESTDATA:+$IBL_TESTDATA/hdri}
HDRI=${HDRI:-tests/data}
IBL=$BUILD/ibl
STUDIES=$BUILD/tools/studies/ibl_studies
DOC=docs/STUDIES.md
IMG=docs/images
WORK=$BUILD/studies
[ -d "$HDRI" ] || { echo "studies: no test HDRIs in $HDRI (set IBL_TESTDATA)" >&2; exit 1; }
[ -x "$STUDIES" ] || { echo "studies: $STUDIES is not built (make build)" >&2; exit 1; }
rm -rf "$WORK"
mkdir -p "$WORK/md" "$IMG"

cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
MACHINE="${cpu:-an unknown CPU} ($(nproc) cores, one thread used), $(uname -s) $(uname -r)"
DATE=$(date -u +%Y-%m-%d)
start=$(date +%s)

"$STUDIES" --hdri "$HDRI" --out "$WORK/md" --images "$IMG" --machine "$MACHINE" --date "$DATE"

# ---- pictures: `ibl render`, one thread, 320 pixels per image; each group's commands go into
# its fragment (paths shown relative to the test HDRIs and the work folder) ----
render() { echo "ibl render -q -j 1 --width 320 $*" | sed "s|$HDRI/||g; s|$WORK/||g" >>"$CMDS"; "$IBL" render -q -j 1 --width 320 "$@"; }
commands() {
    { echo '```sh'; cat "$CMDS"; echo '```'; echo; echo "Rendered on $MACHINE, $DATE."; } >"${CMDS%.cmd}.md"
    rm "$CMDS"
}
# the HDR IBL artefact: AO alone against tri-Ace's SO (3) under a low sun, AO 0.1 at the bottom
CMDS=$WORK/md/pictures_so.cmd
render "$HDRI/sunset.exr" -o "$IMG/studies_so.png" --sphere-ao 0.1 --compare so=ao so=triace-fast
commands
# specular occlusion off and on with the AS (2) composition; AmbientBRDF off / on (SH
# diffuse, the bake's chain and split-sum table; the volume written by `ibl lut` with a stated
# range); the irradiance map (the bake itself, AmbientBRDF on); the Monte Carlo reference
CMDS=$WORK/md/pictures_ambient.cmd
render "$HDRI/forest.exr" -o "$IMG/studies_so_mix.png" --sphere-ao 0.2 --compare so=none so=triace-fast,mix=lerp-ao
"$IBL" bake -q -j 1 "$HDRI/interior.exr" -o "$WORK/bake-interior"
echo "ibl bake interior.exr -o bake-interior" >>"$CMDS"
B=$WORK/bake-interior
# one exposure for the four interior pictures (automatic exposure would hide the differences)
render "$HDRI/interior.exr" --chain "$B/specular.ktx2" --lut "$B/brdf_lut.ktx2" --exposure -2.5 -o "$IMG/studies_ambient_off.png"
"$IBL" lut -q -j 1 --kind ambient-brdf --shininess-range 1:100000 -o "$WORK/ambient_brdf.ktx2"
echo "ibl lut --kind ambient-brdf --shininess-range 1:100000 -o ambient_brdf.ktx2" >>"$CMDS"
render "$HDRI/interior.exr" --chain "$B/specular.ktx2" --lut "$B/brdf_lut.ktx2" --ambient "$WORK/ambient_brdf.ktx2" \
    --ambient-range 1:100000 --exposure -2.5 -o "$IMG/studies_ambient_on.png"
render "$B" --environment "$HDRI/interior.exr" --exposure -2.5 -o "$IMG/studies_iem.png"
render "$HDRI/interior.exr" --reference --samples 64 --exposure -2.5 -o "$IMG/studies_reference.png"
commands

# ---- the pictures' sizes: each at most 200 KB ----
for f in "$IMG"/studies_*.png; do
    size=$(wc -c <"$f")
    [ "$size" -le 204800 ] || { echo "studies: $f is $size bytes (over 200 KB)" >&2; exit 1; }
done

# ---- splice each fragment between its markers ----
for frag in "$WORK"/md/*.md; do
    name=$(basename "$frag" .md)
    grep -q "<!-- studies:$name -->" "$DOC" || { echo "studies: no marker for $name in $DOC" >&2; exit 1; }
    awk -v name="$name" -v frag="$frag" '
        $0 == "<!-- studies:" name " -->" { print; while ((getline line < frag) > 0) print line; skip = 1; next }
        $0 == "<!-- /studies:" name " -->" { skip = 0 }
        !skip { print }' "$DOC" >"$WORK/STUDIES.md"
    cp "$WORK/STUDIES.md" "$DOC"
done
echo "studies: $DOC and $IMG/studies_*.png regenerated in $(( $(date +%s) - start )) s"
