#include "audit_command.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "option_parsing.hpp"

namespace geoanchor::cli {

CLI::App* add_audit_command(CLI::App& app, AuditCommandOptions& o) {
  auto* cmd = app.add_subcommand("audit", "Check a finished map (tiles, vector maps, sidecars, transform files) against "
                                          "the geodetic rules of a safety case: a PASS/FAIL line with evidence per check");
  auto& r = o.request;
  auto& l = r.limits;
  cmd->add_option("MAP", r.inputs, "The map's folders (recursive), tiles, vector maps, sidecars and transform files")->required();
  cmd->add_option("--checkpoints", r.checkpoints,
                  "Control set of surveyed checkpoints (source and target coordinates, as fit reads): each source "
                  "position through the map's transform against its target");
  cmd->add_option("--checkpoints-dst", r.checkpoints_dst,
                  "The surveyed checkpoints in a file of their own: --checkpoints then holds them as the map has them "
                  "(joined by id, as fit --src/--dst; ENU columns at the map's origin)")
      ->needs("--checkpoints");
  cmd->add_flag("--json", o.json, "Write the audit as JSON (schema geoanchor.audit/1) on standard output");
  cmd->add_option("--exclude", r.exclude, "Leave out files matching GLOB (repeatable), as apply's --exclude");
  cmd->add_option("--max-checkpoint-horizontal-m", l.checkpoint_horizontal_m,
                  "Largest horizontal checkpoint residual (default 0.05 m, the airside requirement)")
      ->check(finite_positive());
  cmd->add_option("--max-checkpoint-vertical-m", l.checkpoint_vertical_m, "Largest vertical checkpoint residual (default 0.05 m)")
      ->check(finite_positive());
  cmd->add_option("--max-seam-m", l.seam_m, "Largest separation where two tiles meet (default 0.01 m)")->check(finite_positive());
  cmd->add_option("--adjacency-gap-m", l.adjacency_gap_m, "Tiles whose bounds come this close share a boundary (default 1 m)")
      ->check(finite_positive());
  cmd->add_option("--min-rtk-fixed-percent", l.min_rtk_fixed_percent, "Smallest RTK-fixed share of a tile or vector map (default 95)")
      ->check(finite_range(0.0, 100.0));
  cmd->add_option("--max-float32-spacing-m", l.float32_resolution_m,
                  "Largest float32 spacing of stored offsets over the extent (default 0.001 m)")
      ->check(finite_positive());
  cmd->add_option("--max-tangent-departure-m", l.tangent_plane_m,
                  "Largest departure d²/2R of the tangent plane from the ellipsoid over the map (default 1 m: 3.6 km)")
      ->check(finite_positive());
  return cmd;
}

int run_audit(const AuditCommandOptions& o) {
  const workflow::AuditResult r = workflow::audit_map(o.request);
  if (o.json) {
    std::cout << workflow::audit_json_text(r, o.request) << "\n";
  } else {
    std::cout << workflow::audit_text(r);
  }
  io::finish_standard_output("the audit");
  if (!r.passed()) {
    std::size_t failed = 0;
    for (const auto& c : r.checks) failed += c.status == workflow::AuditStatus::fail ? 1 : 0;
    std::cerr << "geoanchor: error[E_AUDIT_FAILED]: " << failed << " of " << r.checks.size()
              << " checks fail (listed above with their evidence)\n";
    return exit_code(ErrorKind::rejected);
  }
  return 0;
}

CLI::App* add_locate_command(CLI::App& app, LocateCommandOptions& o) {
  auto* cmd = app.add_subcommand("locate", "The audit trail of labelled map points: ENU at the map's origin -> geodetic in "
                                           "the map's frame (and another frame and epoch), with propagated sigmas");
  cmd->add_option("MAP", o.map, "The map: a folder, a tile or vector map (with its sidecar), or a sidecar")->required();
  cmd->add_option("POINTS", o.request.points, "CSV with columns id,e_m,n_m,u_m: ENU at the map's origin")->required();
  cmd->add_option("--to", o.request.to, "Also in this frame, FRAME[@EPOCH] (frame catalog)");
  cmd->add_option("--plate", o.request.plate, "The plate the points are on, for an epoch change (EURA, NOAM, ...)");
  cmd->add_option("--plate-model", o.request.plate_model, "ITRF2020 (default) | ITRF2014");
  cmd->add_option("--exclude", o.request.exclude, "Leave out files of the map's folder matching GLOB (repeatable)");
  cmd->add_option("--max-extrapolation", o.request.max_extrapolation_m,
                  "Refuse points farther than this (m) outside the control network of the map's transform (without "
                  "one: from the map's ENU origin; default 10000)")
      ->check(finite_range(0.0, 1e7));
  cmd->add_option("-o,--output", o.output, "Output CSV (default: standard output)");
  cmd->add_flag("--json", o.json, "Write JSON (schema geoanchor.locate/1) instead of CSV");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output file");
  return cmd;
}

void run_locate(const LocateCommandOptions& o) {
  workflow::LocateRequest request = o.request;
  request.map = {o.map};
  const workflow::LocateResult r = workflow::locate_points(request);
  const std::string text = o.json ? workflow::locate_json_text(r) + "\n" : workflow::locate_csv(r);
  if (o.output == "-") {
    std::cout << text;
    io::finish_standard_output("the located points");
    return;
  }
  io::AtomicOutputFile out(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  out.stream() << text;
  out.commit();
}

}  // namespace geoanchor::cli
