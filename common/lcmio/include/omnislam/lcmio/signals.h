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
/// How many SIGINT / SIGTERM were received (a second one can cut short what a stop still does).
int stopSignalCount();

}  // namespace omnislam::lcmio
