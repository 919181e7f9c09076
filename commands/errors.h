// The error types every command throws, as apps/ptc maps them to exit codes: UsageError -> 2,
// InputError and any other failure -> 1, Interrupted (a Ctrl-C or SIGTERM, toolkit/core/cancel.h)
// -> 130 (toolkit/core/error.h and cancel.h define them for every layer).
#pragma once

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
