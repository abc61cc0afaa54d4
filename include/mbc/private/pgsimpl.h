/* Kept for the FCLIB reader's include until it moves beside the multiplier solve. */
#pragma once
#include <mbc/private/multiplierimpl.h>
