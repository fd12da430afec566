/* madvise, MAP_ANONYMOUS and MAP_NORESERVE are BSD/Linux extensions beyond POSIX */
#define _DEFAULT_SOURCE
#include "arena.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

/* The CLI's allocator for the library.
 *
 * A command allocates a few dozen large buffers (cubes, pyramid records, precomputed weights),
 * frees some and allocates others. Every fresh page costs the kernel a fault and a zeroing:
 * measured on the 256 GGX chain, clear_page alone was 11% of the command's CPU time when each
 * large buffer had its own mapping (docs/PERFORMANCE.md "Specular prefilter"). So blocks of
 * ARENA_MIN bytes and more come from one arena, reserved once (address space only), advised
 * as transparent huge pages (one fault per 2 MiB), and a freed block is kept for the next
 * request it fits (best fit, split, merged with free neighbours) instead of being returned:
 * a command's memory is touched about once. Smaller blocks come from malloc. If the arena
 * cannot be reserved (strict overcommit) or is full, large blocks fall back to malloc too, as
 * they do in AddressSanitizer builds.
 *
 * Every block has a header: its size and whether it is in the arena. Free arena blocks form a
 * list sorted by address, so that neighbours merge. One mutex: the library allocates from its
 * worker threads as well, but rarely (a few hundred calls per command). */

enum { HEADER = 64 };
#define ARENA_MIN ((size_t)64 << 10)
#define ARENA_ALIGN ((size_t)2 << 20)
#define ARENA_RESERVE ((size_t)64 << 30)

typedef struct block {
    size_t size;  /* bytes, header included */
    size_t arena; /* 1: in the arena */
    struct block *next; /* free list, by address */
} block;

static struct {
    pthread_mutex_t lock;
    int tried;
    char *base, *top, *end; /* reserved [base, end), handed out [base, top) */
    block *free;
} arena = {PTHREAD_MUTEX_INITIALIZER, 0, NULL, NULL, NULL, NULL};

/* AddressSanitizer sees overruns of malloc'd blocks only: its builds keep every block there */
#if defined(__SANITIZE_ADDRESS__)
#define ARENA_USABLE 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ARENA_USABLE 0
#endif
#endif
#if !defined(ARENA_USABLE) && defined(__linux__) && defined(MADV_HUGEPAGE)
#define ARENA_USABLE 1
#endif

static int arena_reserve(void)
{
#if ARENA_USABLE
    size_t span = ARENA_RESERVE + ARENA_ALIGN;
    char *map = mmap(NULL, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (map == MAP_FAILED) return 0;
    arena.base = (char *)(((uintptr_t)map + ARENA_ALIGN - 1) & ~(uintptr_t)(ARENA_ALIGN - 1));
    arena.top = arena.base;
    arena.end = arena.base + ARENA_RESERVE;
    madvise(arena.base, ARENA_RESERVE, MADV_HUGEPAGE); /* advice only: failure changes nothing */
    return 1;
#else
    return 0;
#endif
}

/* a block of `size` bytes (header included, a multiple of ARENA_MIN) from the arena, or NULL */
static block *arena_take(size_t size)
{
    block **best = NULL;
    for (block **b = &arena.free; *b; b = &(*b)->next)
        if ((*b)->size >= size && (!best || (*b)->size < (*best)->size)) best = b;
    if (best) {
        block *b = *best;
        if (b->size - size >= ARENA_MIN) { /* the rest stays free, in place in the list */
            block *rest = (block *)((char *)b + size);
            rest->size = b->size - size;
            rest->arena = 1;
            rest->next = b->next;
            *best = rest;
            b->size = size;
        } else {
            *best = b->next;
        }
        return b;
    }
    if ((size_t)(arena.end - arena.top) < size) return NULL;
    block *b = (block *)arena.top;
    arena.top += size;
    b->size = size;
    b->arena = 1;
    return b;
}

static void arena_give(block *b)
{
    block **at = &arena.free;
    while (*at && *at < b) at = &(*at)->next;
    b->next = *at;
    *at = b;
    if (b->next && (char *)b + b->size == (char *)b->next) { /* merge with the next */
        b->size += b->next->size;
        b->next = b->next->next;
    }
    if (at != &arena.free) { /* merge with the previous: its next field is `at` */
        block *prev = (block *)((char *)at - offsetof(block, next));
        if ((char *)prev + prev->size == (char *)b) {
            prev->size += b->size;
            prev->next = b->next;
        }
    }
}

void *cli_arena_alloc(size_t bytes, void *user)
{
    (void)user;
    if (bytes > SIZE_MAX - HEADER - ARENA_MIN) return NULL;
    if (bytes + HEADER >= ARENA_MIN) {
        size_t size = (bytes + HEADER + ARENA_MIN - 1) & ~(ARENA_MIN - 1);
        pthread_mutex_lock(&arena.lock);
        if (!arena.tried) arena.tried = 1, arena_reserve();
        block *b = arena.base ? arena_take(size) : NULL;
        pthread_mutex_unlock(&arena.lock);
        if (b) return (char *)b + HEADER;
    }
    void *p = NULL;
    if (posix_memalign(&p, 64, bytes + HEADER) != 0) return NULL;
    block *b = p;
    b->size = bytes + HEADER;
    b->arena = 0;
    return (char *)p + HEADER;
}

void cli_arena_free(void *ptr, void *user)
{
    (void)user;
    if (!ptr) return;
    block *b = (block *)((char *)ptr - HEADER);
    if (!b->arena) {
        free(b);
        return;
    }
    pthread_mutex_lock(&arena.lock);
    arena_give(b);
    pthread_mutex_unlock(&arena.lock);
}
