#pragma once
// Whether a command's standard output failed because its reader chose to stop reading.

namespace pintag::cli {

/// The exit status of a command whose reader left before the output was all written: what a shell
/// reports for a process that SIGPIPE ended (128 + 13), as `seq 100000 | head -1` gives.
inline constexpr int kReaderGoneStatus = 141;

/// True when standard output is a pipe or socket with no one left to read it (`pintag keys export
/// | head -1`): the reader chose to stop, so the lost rest is not an error to report, unlike a
/// full disk. SIGPIPE is ignored in `pintag`, so the write fails with EPIPE instead of ending the
/// command, and this asks the descriptor itself rather than trusting errno after iostreams.
bool StandardOutputReaderHasGone();

}  // namespace pintag::cli
