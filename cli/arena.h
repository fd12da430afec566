#ifndef IBL_CLI_ARENA_H
#define IBL_CLI_ARENA_H
#include <stddef.h>

/* The allocator the CLI gives the library (ibl_allocator's signatures): large blocks from one
 * huge-page arena whose freed blocks are reused (arena.c says why). Thread-safe. */
void *cli_arena_alloc(size_t bytes, void *user);
void cli_arena_free(void *ptr, void *user);

#endif
