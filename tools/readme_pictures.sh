#!/usr/bin/env bash
# Make every picture the README and its chapters (docs/*.md) show, into docs/, with the settings written here (one command:
# `tools/readme_pictures.sh`, from anywhere; about 2 minutes on 2 cores). Run it after a change
# that alters images, look at the pictures, and commit them: `*.png` is ignored by .gitignore
# except under docs/, and tests/suite/architecture.rs fails on a README picture that git does not track.
#
# The renders use the shipped scenes at their scene.toml sizes and fixed seeds, so a rerun on the
# same code gives the same files.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
vrpt=target/release/vrpt
out=docs
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Veach's picture (docs/lights.md, "Light sampling and MIS"): the glossy plates at 64 spp, stratified
# points, Phong directions, BSDF sampling / light sampling / MIS.
for lights in bsdf nee mis; do
    $vrpt render scenes/glossy-plates --spp 64 --seed 1 -q \
        --sampler stratified --directions phong --lights "$lights" \
        -o "$out/glossy-plates-$lights.png"
done

# The Cornell box at 64 spp: BSDF sampling only (the `combined` preset) and the default.
$vrpt render scenes/cornell-box --spp 64 --seed 1 -q --strategy combined \
    -o "$out/cornell-box-bsdf-64spp.png"
$vrpt render scenes/cornell-box --spp 64 --seed 1 -q -o "$out/cornell-box-mis-64spp.png"

# Sobol against padded strata on lit-checker (docs/samplers.md, "Stratifying whole paths"): a 16384-spp
# Sobol reference, then independent / stratified / Sobol with NEE at 4..1024 spp, 4 runs each,
# with points uniform by area on the light (the 4D integrand with edges the section is about).
$vrpt render scenes/lit-checker --spp 16384 --sampler sobol --lights nee --seed 1000 -q \
    -o "$work/lc-ref.exr"
$vrpt converge scenes/lit-checker --reference "$work/lc-ref.exr" --runs 4 -q \
    --strategies independent+cosine+nee+area+power,stratified+cosine+nee+area+power,sobol+cosine+nee+area+power \
    --spp 4,16,64,256,1024 --plot "$out/lit-checker-converge.png" >/dev/null

# Many lights (docs/lights.md, "Many lights: the light tree"): the night hall at 16 spp with lights
# chosen by power and by the tree (the default), and a 1024-spp image of it.
for choice in power tree; do
    $vrpt render scenes/night-hall --spp 16 --seed 1 -q --light-choice "$choice" \
        -o "$out/night-hall-$choice-16spp.png"
done
$vrpt render scenes/night-hall --spp 1024 --seed 1 -q -o "$out/night-hall-1024spp.png"

# Path guiding (docs/guiding.md): the gap and the door at equal time (20 s each, the
# guided render's training included) with Phong directions and guided ones (MIS both), and what
# the guide learned at a point of each dark room's floor beside the brute-force incident
# radiance there. Time-limited: the spp, not the look, depend on the machine.
for scene in gap door; do
    for d in phong guided; do
        $vrpt render "scenes/$scene" --spp 1000000 --time-limit 20 --seed 1 -q --directions "$d" \
            -o "$out/$scene-$d-20s.png"
    done
done
$vrpt guide scenes/gap --pixel 70,170 --spp 512 --brute-spp 256 -o "$out/gap-guide.png" >/dev/null
$vrpt guide scenes/door --pixel 96,170 --spp 512 --brute-spp 256 -o "$out/door-guide.png" >/dev/null

# Error estimates (docs/error.md, "How good is this image"): the calibration plot, and where an adaptive
# render of glossy-plates spends its samples.
cargo run --release -q --example calibration -- --size 64 48 --spp 64 --ref-spp 8192 --seeds 3 \
    --plot "$out/calibration.png" >/dev/null
$vrpt render scenes/glossy-plates --width 128 --height 96 --spp 256 --seed 1 --adaptive -q \
    -o "$work/gp-adaptive.png" --spp-map "$out/glossy-plates-spp-map.png"

# An HDR sky (docs/lights.md, "An HDR sky"): sun-sky at 16 spp with the map's importance sampling (the
# default) and with the cosine (--light-points area), and a 1024-spp image.
$vrpt render scenes/sun-sky --width 256 --height 192 --spp 1024 -q -o "$out/sun-sky.png"
$vrpt render scenes/sun-sky --width 256 --height 192 --spp 16 --seed 1 -q \
    -o "$out/sun-sky-16spp-map.png"
$vrpt render scenes/sun-sky --width 256 --height 192 --spp 16 --seed 1 -q --light-points area \
    -o "$out/sun-sky-16spp-cosine.png"

# Textures (docs/scenes.md, "Textures, cutouts and bump maps"): the textured scene at 256 spp.
$vrpt render scenes/textured --width 256 --height 192 --spp 256 --seed 1 -q -o "$out/textured.png"

# The theory (README "The theory, by command"): 256 points of each sampler in the pixel's
# dimensions with the dependent pair, the strata and the independence box drawn, their
# periodograms, spectra and discrepancy curves over 16 sets; the same points after the cosine
# warp; every warp against its pdf; the variance of known integrals against N, and the
# lecture's Figure 2 (the curve sampled without and with strata, N = 8).
$vrpt points --n 256 --dependent -o "$out/points.png" >/dev/null
$vrpt points --n 256 --warp cosine -o "$out/points-cosine.png" >/dev/null
$vrpt warptest -o "$out/warps.png" >/dev/null
$vrpt integrate --n 16,64,256,1024 -o "$out/integrals.png" --figure "$out/figure2.png" >/dev/null

# Scenes made elsewhere (docs/scenes.md) and the glass scene against Mitsuba 3 are made by
# tools/peers/mitsuba_check.py --docs (needs Mitsuba 3) and by hand from public OBJ files (the
# chapter says which); they are not redrawn here.

ls -l "$out"/*.png
