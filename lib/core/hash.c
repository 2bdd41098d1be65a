/* Bulk hashing through libxxhash's XXH3, for the contents of scenes and environment maps (the
 * job hash that --resume compares); rb_hash64 (err.c) stays the small, dependency-free hash. */
#include "core/core.h"

#include <xxhash.h>

uint64_t rb_hash_bulk(const void *data, size_t size, uint64_t seed)
{
    return XXH3_64bits_withSeed(size ? data : "", size, seed);
}
