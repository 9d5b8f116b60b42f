// SIGINT / SIGTERM as a stop request for the processes' event loops.
//
// A signal handler can only reach process-wide state, so the request is one atomic flag (the only
// global of this library). The loops poll stopRequested() between LCM events (LcmNode::spin).
#pragma once

namespace livo {

/// Installs handlers for SIGINT and SIGTERM that set the stop flag (a second signal gets the default
/// action, so a stuck process can still be interrupted). SIGPIPE is ignored.
void installStopHandlers();
/// True once SIGINT or SIGTERM arrived (or requestStop() was called).
bool stopRequested();
/// The signal that requested the stop (0 when none, or requested from code).
int stopSignal();
/// For tests and in-process shutdown.
void requestStop();
void clearStopRequest();

}  // namespace livo
