#pragma once
// `geoanchor audit` (the geodetic checks a finished map must pass) and
// `geoanchor locate` (the audit trail of labelled map points). See
// docs/commands/audit.md and docs/commands/locate.md.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/workflow/audit.hpp"
#include "geoanchor/workflow/locate.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct AuditCommandOptions {
  workflow::AuditRequest request;
  bool json = false;
};

CLI::App* add_audit_command(CLI::App& app, AuditCommandOptions& options);
// 0 when every check passes, 4 (rejected) when one fails.
int run_audit(const AuditCommandOptions& options);

struct LocateCommandOptions {
  std::string map;
  workflow::LocateRequest request;
  std::string output = "-";
  bool json = false;
  bool overwrite = false;
};

CLI::App* add_locate_command(CLI::App& app, LocateCommandOptions& options);
void run_locate(const LocateCommandOptions& options);

}  // namespace geoanchor::cli
