#!/usr/bin/env bash
# Sets up, builds in Release and runs the main job on the bundled example:
#  1. fit: a 7-parameter transform from the LSZH control marks known in two
#     frames (fixtures/airport_control.csv, with a planted blunder): first as
#     given, where the blunder is flagged and the failing global test refuses
#     the transform (exit 4); then with --remove-outliers, which removes it by
#     data snooping, printing the report and writing the transform file;
#  2. apply: the fitted transform moves the bundled LiDAR tile
#     (fixtures/airport_tile.las, ENU at the LSZH reference point in
#     ITRF2014@2024.5, frame stated by its sidecar) into ETRF2000@2024.5,
#     writing the new tile, its provenance sidecar and the run summary;
#  3. report: the fit's report and PNGs of the workbench's views (off-screen);
#  4. convert: the airport marks go geodetic -> ECEF -> ENU (at the LSZH
#     reference point) -> ECEF -> geodetic, and the round trip is measured;
#  5. adjust -> fit -> apply: the airport's control network
#     (fixtures/airport_network: GNSS baselines to two reference stations
#     and a terrestrial traverse) is adjusted in ITRF2014@2024.5; the LiDAR
#     map's origin is corrected by fitting the marks as the map sees them to
#     the adjusted stations (enu-origin), and the map is moved with it: the
#     two LiDAR tiles, the GeoJSON apron layer and the Lanelet2 lane, with
#     the survey's metadata (fixtures/lszh_survey.json);
#  6. audit: the moved map's geodetic checks (metadata contract, one frame,
#     seams, checkpoints, RTK-fixed share, storage, tangent plane, Web
#     Mercator), each PASS or FAIL with its evidence.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
cmake --preset release >/dev/null
# The command-line program alone: the example needs no test, benchmark or
# window (scripts/test.sh builds everything).
cmake --build --preset release --target geoanchor

geoanchor=build/release/cli/geoanchor
out=build/example
origin=47.464722,8.549167,480   # LSZH aerodrome reference point; ellipsoidal height, WGS 84
mkdir -p "$out"

echo "== fit =="
# As given: every mark is tested and kept; the planted blunder is flagged,
# and the global test failing high refuses the transform (exit 4).
if "$geoanchor" fit fixtures/airport_control.csv --model helmert7 --convention position_vector \
  -o "$out/lszh_helmert7.json" --overwrite >"$out/fit_as_given.txt" 2>&1; then
  echo "unexpected: the control set with its planted blunder passed" >&2
  exit 1
fi
grep -E "flagged|E_FIT_GLOBAL_TEST" "$out/fit_as_given.txt" | grep -vE "^ +P[0-9]+ .* used" | sed 's/^ */  /'
echo
# With --remove-outliers data snooping removes it (strongest evidence first) and fits again.
"$geoanchor" fit fixtures/airport_control.csv --model helmert7 --convention position_vector --remove-outliers \
  -o "$out/lszh_helmert7.json" --overwrite
echo
echo "== apply =="
mkdir -p "$out/tiles"
"$geoanchor" apply fixtures/airport_tile.las --transform "$out/lszh_helmert7.json" --out-dir "$out/tiles" --overwrite
echo "the new tile's frame, origin and provenance ($out/tiles/airport_tile.las.geoanchor.json):"
grep -E '"(frame|transform_sha256|transform_sigma0|sigma_[enu]_m|distance_outside_control_m|points)"' \
  "$out/tiles/airport_tile.las.geoanchor.json" | sed 's/^ */  /'

echo
echo "== report =="
# The fit's text report and a PNG of each workbench view, rendered off-screen
# (no display needed); `geoanchor gui` shows the same views in a window.
"$geoanchor" report fixtures/airport_control.csv --transform "$out/lszh_helmert7.json" -o "$out/report" --overwrite
grep -E "differ by|σ0 =|global test| removed " "$out/report/report.txt" | sed 's/^ */  /'

echo
echo "== diagnose =="
# The same control set with its target heights made orthometric (a planted
# classic mistake): which one it is, and how large.
"$geoanchor" diagnose fixtures/airport_control_orthometric.csv | grep -E "^verdict|^  +1 "

echo
echo "== convert =="

"$geoanchor" convert fixtures/airport_points.csv --to ecef -o "$out/points_ecef.csv" --overwrite
"$geoanchor" convert "$out/points_ecef.csv" --to enu --origin "$origin" -o "$out/points_enu.csv" --overwrite
"$geoanchor" convert "$out/points_enu.csv" --to ecef --origin "$origin" -o "$out/points_ecef_again.csv" --overwrite
"$geoanchor" convert "$out/points_ecef_again.csv" --to geodetic -o "$out/points_geodetic_again.csv" --overwrite
"$geoanchor" convert "$out/points_geodetic_again.csv" --to ecef -o "$out/points_ecef_final.csv" --overwrite

echo
echo "ENU at the reference point (first rows, millimetres):"
"$geoanchor" convert "$out/points_ecef.csv" --to enu --origin "$origin" --precision 3 | grep -v '^#' | head -6
echo
# The largest ECEF difference after the whole round trip, per axis.
paste -d, "$out/points_ecef.csv" "$out/points_ecef_final.csv" | grep -v '^#' | awk -F, '
  NR == 1 { for (i = 1; i <= NF; i++) col[$i] = col[$i] ? col[$i] : i; n = NF / 2; next }
  { for (a = 2; a <= 4; a++) { d = $a - $(a + n); if (d < 0) d = -d; if (d > worst) worst = d } rows++ }
  END { printf "round trip geodetic -> ECEF -> ENU -> ECEF -> geodetic -> ECEF over %d marks: worst axis difference %.3g m\n", rows, worst }'

echo
echo "== adjust -> fit -> apply =="
# The control network: 2 reference stations (one GNSS point cluster), 16
# baselines, a traverse of direction sets, slope distances and zenith angles.
net=fixtures/airport_network
"$geoanchor" adjust "$net/lszh_network.json" -o "$out/lszh_stations.csv" --measurements "$out/lszh_measurements.csv" \
  --report "$out/lszh_adjust.txt" --sinex "$out/lszh_stations.snx" --overwrite
grep -E "vtpv|global test" "$out/lszh_adjust.txt" | sed 's/^ */  /'
# The marks as the map sees them (ENU at the nominal origin) against the
# adjusted stations: the map origin's shift and yaw (planted by the
# generator: E 0.412, N -0.287, U 0.153 m, yaw 14.0 arcsec).
"$geoanchor" fit --src "$net/lszh_marks_map.csv" --dst "$out/lszh_stations.csv" --model enu-origin --origin "$origin" \
  --survey-metadata fixtures/lszh_survey.json -o "$out/lszh_map_origin.json" --overwrite | grep -E "shift_|yaw_|σ0 =|global test" | sed 's/^ */  /'
mkdir -p "$out/network_tiles"
"$geoanchor" apply fixtures/airport_tile.las fixtures/airport_tile_east.csv fixtures/airport_apron.geojson fixtures/airport_lanes.osm \
  --from-frame ITRF2014@2024.5 --transform "$out/lszh_map_origin.json" --survey-metadata fixtures/lszh_survey.json \
  --out-dir "$out/network_tiles" --overwrite
grep -E '"(transform_model|sigma_[enu]_m|distance_outside_control_m)"' "$out/network_tiles/airport_tile.las.geoanchor.json" | sed 's/^ */  /'

echo
echo "== audit =="
# The marks as the map has them against the adjusted stations serve as
# checkpoints here (they are the fit's own marks; a real audit uses others).
"$geoanchor" audit "$out/network_tiles" "$out/lszh_map_origin.json" \
  --checkpoints "$net/lszh_marks_map.csv" --checkpoints-dst "$out/lszh_stations.csv" | grep -E "^(PASS|FAIL|----)|^audit:"
echo "outputs and their provenance sidecars (*.geoanchor.json) are in $out/"
