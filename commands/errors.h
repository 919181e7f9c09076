// The error types every command throws, as apps/ptc maps them to exit codes: UsageError -> 2,
// InputError and any other failure -> 1 (toolkit/core/error.h defines them for every layer).
#pragma once

#include "toolkit/core/error.h"
