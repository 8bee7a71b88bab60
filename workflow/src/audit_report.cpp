// The report of a map's audit: the text `geoanchor audit` prints and its
// JSON (schema geoanchor.audit/1).
#include <nlohmann/json.hpp>

#include <sstream>

#include "audit_text.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow {

using json = nlohmann::ordered_json;
using audit_detail::join;

std::string audit_text(const AuditResult& r) {
  std::ostringstream out;
  std::size_t tiles = 0, vectors = 0, transforms = 0;
  for (const auto& a : r.artifacts) {
    (a.kind == AuditArtifactKind::tile ? tiles : a.kind == AuditArtifactKind::vector_map ? vectors : transforms) += 1;
  }
  out << "geoanchor audit: " << r.artifacts.size() << " artifacts (" << tiles << " tiles, " << vectors << " vector maps, "
      << transforms << " transform files)\n";
  std::size_t failed = 0;
  for (const auto& c : r.checks) {
    const char* verdict = c.status == AuditStatus::pass ? "PASS" : c.status == AuditStatus::fail ? "FAIL" : "----";
    if (c.status == AuditStatus::fail) ++failed;
    out << verdict << "  " << c.name << ": " << c.summary << "\n";
    out << "      limit: " << c.limit << "\n      rule: " << c.rule << "\n";
    for (const auto& e : c.evidence) out << "      - " << e << "\n";
  }
  std::vector<std::string> failing, not_run;
  for (const auto& c : r.checks) {
    if (c.status == AuditStatus::fail) failing.push_back(c.name);
    if (c.status == AuditStatus::not_run) not_run.push_back(c.name);
  }
  const std::size_t ran = r.checks.size() - not_run.size();
  out << "audit: " << (failed == 0 ? "PASSED" : "FAILED") << " (" << ran - failed << " of " << ran << " checks pass";
  if (!failing.empty()) out << "; failing: " << join(failing);
  if (!not_run.empty()) out << "; not run: " << join(not_run);
  out << ")\n";
  return out.str();
}

std::string audit_json_text(const AuditResult& r, const AuditRequest& request) {
  json j;
  j["schema"] = "geoanchor.audit/1";
  j["passed"] = r.passed();
  json arts = json::array();
  for (const auto& a : r.artifacts) {
    arts.push_back({{"path", a.path.string()},
                    {"kind", std::string(to_string(a.kind))},
                    {"sidecar", a.sidecar.empty() ? json(nullptr) : json(a.sidecar.string())},
                    {"readable", a.unreadable.empty()}});
  }
  j["artifacts"] = arts;
  j["ignored"] = r.ignored;
  const AuditLimits& l = request.limits;
  j["limits"] = {{"checkpoint_horizontal_m", l.checkpoint_horizontal_m}, {"checkpoint_vertical_m", l.checkpoint_vertical_m},
                 {"seam_m", l.seam_m},
                 {"min_rtk_fixed_percent", l.min_rtk_fixed_percent},
                 {"float32_spacing_m", l.float32_resolution_m},
                 {"tangent_departure_m", l.tangent_plane_m},
                 {"adjacency_gap_m", l.adjacency_gap_m}};
  json checks = json::array();
  for (const auto& c : r.checks) {
    checks.push_back({{"name", c.name},
                      {"status", std::string(to_string(c.status))},
                      {"summary", c.summary},
                      {"limit", c.limit},
                      {"rule", c.rule},
                      {"evidence", c.evidence}});
  }
  j["checks"] = checks;
  return j.dump(2);
}

}  // namespace geoanchor::workflow
