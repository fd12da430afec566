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
 * Kept, but not without end: freed arena memory whose pages are still there is counted, and
 * beyond ARENA_KEEP bytes the largest such free blocks are given back to the kernel
 * (madvise MADV_DONTNEED: the address range stays reserved, its pages are dropped at once, so
 * the RSS falls; the next use faults in zeroed pages). ARENA_KEEP is above what the usual
 * commands ever free (the 512 GGX chain peaks at 193 MB), so their reuse is untouched; a 16k
 * input's 2 GiB image, freed once it is a cube, goes back.
 *
 * Every block has a header: its size and whether it is in the arena. Free arena blocks form a
 * list sorted by address, so that neighbours merge. One mutex: the library allocates from its
 * worker threads as well, but rarely (a few hundred calls per command). */

enum { HEADER = 64 };
#define ARENA_MIN ((size_t)64 << 10)
#define ARENA_ALIGN ((size_t)2 << 20)
#define ARENA_RESERVE ((size_t)64 << 30)
#define ARENA_KEEP ((size_t)256 << 20)

typedef struct block {
    size_t size;     /* bytes, header included */
    size_t arena;    /* 1: in the arena */
    struct block *next; /* free list, by address */
    size_t resident; /* free blocks: at most this many of its bytes still have pages */
} block;

static struct {
    pthread_mutex_t lock;
    int tried;
    char *base, *top, *end; /* reserved [base, end), handed out [base, top) */
    block *free;
    size_t kept; /* the sum of the free blocks' resident bytes */
} arena = {PTHREAD_MUTEX_INITIALIZER, 0, NULL, NULL, NULL, NULL, 0};

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
        /* where in a block its resident pages are is not known: the part taken is assumed to
         * hold as many of them as fit, the rest keeps what remains */
        size_t taken = b->resident < size ? b->resident : size;
        if (b->size - size >= ARENA_MIN) { /* the rest stays free, in place in the list */
            block *rest = (block *)((char *)b + size);
            rest->size = b->size - size;
            rest->arena = 1;
            rest->next = b->next;
            rest->resident = b->resident - taken;
            *best = rest;
            b->size = size;
        } else {
            *best = b->next;
            taken = b->resident;
        }
        arena.kept -= taken;
        return b;
    }
    if ((size_t)(arena.end - arena.top) < size) return NULL;
    block *b = (block *)arena.top;
    arena.top += size;
    b->size = size;
    b->arena = 1;
    return b;
}

/* Drops the pages of a free block, all but the one holding its header. */
static void arena_release(block *b)
{
    const uintptr_t page = 4096;
    uintptr_t from = ((uintptr_t)b + HEADER + page - 1) & ~(page - 1);
    uintptr_t to = ((uintptr_t)b + b->size) & ~(page - 1);
    if (to > from && madvise((void *)from, to - from, MADV_DONTNEED) == 0) {
        arena.kept -= b->resident;
        b->resident = 0;
    }
}

/* Gives back the free blocks with the most resident bytes until at most ARENA_KEEP are kept. */
static void arena_trim(void)
{
    while (arena.kept > ARENA_KEEP) {
        block *most = NULL;
        for (block *b = arena.free; b; b = b->next)
            if (b->resident && (!most || b->resident > most->resident)) most = b;
        if (!most) break;
        size_t before = arena.kept;
        arena_release(most);
        if (arena.kept == before) break; /* madvise refused: keep the pages */
    }
}

static void arena_give(block *b)
{
    b->resident = b->size; /* it was in use: every page may have been touched */
    arena.kept += b->size;
    block **at = &arena.free;
    while (*at && *at < b) at = &(*at)->next;
    b->next = *at;
    *at = b;
    if (b->next && (char *)b + b->size == (char *)b->next) { /* merge with the next */
        b->size += b->next->size;
        b->resident += b->next->resident;
        b->next = b->next->next;
    }
    if (at != &arena.free) { /* merge with the previous: its next field is `at` */
        block *prev = (block *)((char *)at - offsetof(block, next));
        if ((char *)prev + prev->size == (char *)b) {
            prev->size += b->size;
            prev->resident += b->resident;
            prev->next = b->next;
        }
    }
    arena_trim();
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
