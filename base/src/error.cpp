#include "geoanchor/base/error.hpp"

namespace geoanchor {

int exit_code(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::usage: return 2;
    case ErrorKind::input: return 3;
    case ErrorKind::rejected: return 4;
    case ErrorKind::io: return 5;
  }
  return 1;
}

}  // namespace geoanchor
