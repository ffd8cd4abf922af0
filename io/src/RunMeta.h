#pragma once
// The /meta group every results.h5 starts with (Results.cpp): program, version, kind, the
// scenario's text and file, the overrides, the command line, the start time, status "running".

#include <io/Results.h>

#include <string>

#include "Hdf5.h"

namespace io {

/// Creates /meta in `file` for a run of the given scenario kind.
h5::Handle createRunMeta(hid_t file, const RunInfo& info, const std::string& kind);
/// Sets /meta's status and message and stamps the time it finished.
void setRunStatus(hid_t meta, const std::string& status, const std::string& message);

}  // namespace io
