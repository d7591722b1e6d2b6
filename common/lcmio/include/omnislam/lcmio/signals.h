// SIGINT / SIGTERM handling: the handler only sets a flag; loops poll stopRequested().
#pragma once

namespace omnislam::lcmio {

/// Installs handlers for SIGINT and SIGTERM (idempotent).
void installStopHandlers();
/// True once SIGINT or SIGTERM was received (or requestStop() called).
bool stopRequested();
void requestStop();
/// The signal that requested the stop, 0 if none.
int stopSignal();

}  // namespace omnislam::lcmio
