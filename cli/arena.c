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
 * The allocator never writes into a block: what it knows of the arena's blocks (start, size,
 * free or not) is kept beside them, in a list of small malloc'd records in address order, and
 * a pointer is told to be the arena's by its address. So a fresh block's pages are first
 * touched by whoever writes its data: the library's workers fill their own rows, and each
 * faults (and the kernel zeroes) its own 2 MiB pages in parallel. A header at the block's
 * start made the allocating thread fault the block's first huge page, serially and inside the
 * mutex (13% of the 256 GGX chain's samples, on a host slow to back fresh memory). The
 * library's ibl_alloc keeps no header in its large blocks either (src/core/context.c): the
 * blocks this returns from the arena start on a page boundary, which is what it asks of them.
 *
 * Kept, but never beside fresh memory: a free block either still has pages ("paged": its user wrote
 * some of it) or has none (never written, or dropped with madvise MADV_DONTNEED: the address range
 * stays reserved, the pages go at once; a later use faults in zeroed ones; of a block the whole 2
 * MiB pages inside it go, and a block with none, a fragment, goes first and whole, see
 * arena_release_for), and free neighbours merge only with their own kind. Which pages a block holds
 * is the kernel's count (mincore), not its size: buffers sized for the worst case (gathered
 * records, bright blocks) are often mostly unwritten, and counting them whole let the 256 GGX
 * chain's output fault in 6.3 MB of fresh pages beside 20 MB of idle freed ones. A request takes
 * the best paged block that fits; whatever part of its bytes has no pages (all of them for a block
 * without pages or address space from the arena's top) is faulted in fresh, so first free blocks
 * with pages are given back (arena_release_for says which), as many resident bytes as that. So the RSS never grows
 * while freed pages sit idle, the peak is about the most the command has in use at once, and freed
 * memory that a later request fits is reused with its pages: giving back the 1024 chain's freed
 * working buffers before the output chain was allocated made the chain fault 95 MB in again, and
 * the 2048 chain ~1.9 GB (bench/bench_stages.c shows each stage's faults).
 *
 * One mutex: the library allocates from its worker threads as well, but rarely (a few hundred
 * calls per command, a few dozen blocks alive at once, so the lists are searched in order). */

#define ARENA_MIN ((size_t)64 << 10)
#define ARENA_ALIGN ((size_t)2 << 20)
#define ARENA_RESERVE ((size_t)64 << 30)
/* The smallest fragment given back (arena_release_for): smaller ones free too little to be
 * worth a split huge page. With every fragment, the Phong chain with cmft's exponents at 256
 * took 7 ms more on two threads than with none (its live blocks on split huge pages); from 256
 * KiB, 2 ms more, at the same peak RSS. */
#define FRAGMENT_MIN ((size_t)256 << 10)

/* One block of the arena, in use or free. The blocks tile [base, top) in address order. */
typedef struct span {
    char *start;
    size_t size;     /* bytes, a multiple of ARENA_MIN */
    int paged;       /* free blocks: its pages may still be there (1) or were dropped (0) */
    int used;
    struct span *prev, *next;
    /* a free block without pages dropped from huge pages shared with blocks in use (a
     * fragment, arena_release_for): the kernel split those huge pages, so its range faults
     * 4 KiB pages; never handed out again (fresh address space faults 2 MiB at once) */
    int split;
} span;

static struct {
    pthread_mutex_t lock;
    int tried;
    char *base, *top, *end; /* reserved [base, end), handed out [base, top) */
    span *first, *last;     /* every block of [base, top), by address */
} arena = {PTHREAD_MUTEX_INITIALIZER, 0, NULL, NULL, NULL, NULL, NULL};

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
    size_t span_bytes = ARENA_RESERVE + ARENA_ALIGN;
    char *map = mmap(NULL, span_bytes, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
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

static int in_arena(const void *p)
{
    return arena.base && (const char *)p >= arena.base && (const char *)p < arena.end;
}

/* Inserts s after `after` (NULL: at the front). */
static void link_after(span *after, span *s)
{
    s->prev = after;
    s->next = after ? after->next : arena.first;
    if (s->next) s->next->prev = s;
    else arena.last = s;
    if (after) after->next = s;
    else arena.first = s;
}

static void unlink_span(span *s)
{
    if (s->prev) s->prev->next = s->next;
    else arena.first = s->next;
    if (s->next) s->next->prev = s->prev;
    else arena.last = s->prev;
    free(s);
}

/* Merges the free block s with its free neighbours of the same kind (paged or not, split or
 * not: a block is one or the other, so what its reuse costs is known); returns the merged
 * block. */
static span *merge_free(span *s)
{
    span *next = s->next, *prev = s->prev;
    if (next && !next->used && next->paged == s->paged && next->split == s->split) {
        s->size += next->size;
        unlink_span(next);
    }
    if (prev && !prev->used && prev->paged == s->paged && prev->split == s->split) {
        prev->size += s->size;
        unlink_span(s);
        s = prev;
    }
    return s;
}

/* Bytes of [p, p + n) whose pages are in memory (mincore; p and n on page boundaries). A
 * block freed after use holds the pages its user wrote, which may be few of its bytes. */
static size_t resident_bytes(const char *p, size_t n)
{
    enum { PAGE = 4096, BATCH = 4096 };
    unsigned char vec[BATCH];
    size_t count = 0;
    for (size_t done = 0; done < n;) {
        size_t bytes = n - done < (size_t)BATCH * PAGE ? n - done : (size_t)BATCH * PAGE;
        /* (mincore fails only for a range not mapped: never the arena's; then count it all) */
        if (mincore((void *)(p + done), bytes, vec) != 0) return count * PAGE + (n - done);
        for (size_t i = 0; i < bytes / PAGE; i++) count += vec[i] & 1;
        done += bytes;
    }
    return count * PAGE;
}

/* The whole huge pages (ARENA_ALIGN bytes, on their boundaries) inside block s: [*from, *to),
 * empty when it holds none. */
static void whole_pages(const span *s, char **from, char **to)
{
    size_t lo = (size_t)(s->start - arena.base), hi = lo + s->size;
    *from = arena.base + ((lo + ARENA_ALIGN - 1) & ~(ARENA_ALIGN - 1));
    *to = arena.base + (hi & ~(ARENA_ALIGN - 1));
    if (*to < *from) *to = *from;
}

/* Drops the pages of the whole huge pages inside the paged free block s: how many of their
 * bytes were in memory (0 if none, or if it failed). Only whole ones: dropping part of a huge
 * page makes the kernel split it into 4 KiB pages, and its range then faults 4 KiB at a time
 * (512 faults where one did) for as long as the process lives. So the few pages at a block's
 * ends that share a huge page with its neighbours stay, as paged free blocks of their own
 * (fragments: the first to go at a later request, arena_release_for).
 * Seen in the 512 GGX chain on two threads, where the order in which the workers allocate
 * moves blocks: level 1's weights landed on such split pages and took ~2,200 faults more than
 * on one thread. */
static size_t arena_release(span *s)
{
    char *from, *to;
    whole_pages(s, &from, &to);
    if (from == to) return 0;
    char *end = s->start + s->size;
    size_t resident = resident_bytes(from, (size_t)(to - from));
    /* the records first, so that a failure leaves the block as it was */
    span *head = NULL, *tail = NULL;
    if (from > s->start && !(head = malloc(sizeof *head))) return 0;
    if (to < end && !(tail = malloc(sizeof *tail))) {
        free(head);
        return 0;
    }
    if (madvise(from, (size_t)(to - from), MADV_DONTNEED) != 0) {
        free(head);
        free(tail);
        return 0;
    }
    if (tail) {
        *tail = (span){to, (size_t)(end - to), 1, 0, NULL, NULL, 0};
        link_after(s, tail);
    }
    if (head) { /* s keeps the head; the dropped middle becomes a block after it */
        *head = (span){from, (size_t)(to - from), 0, 0, NULL, NULL, 0};
        link_after(s, head);
        s->size = (size_t)(from - s->start);
        s = head;
    } else {
        s->size = (size_t)(to - from);
    }
    s->paged = 0;
    merge_free(s);
    return resident;
}

/* Drops the pages of the paged free block s, which holds no whole huge page (a fragment), and
 * adds how many bytes of it were in memory to *released; 0 if madvise refused. Its huge pages
 * are shared with its neighbours, and the kernel splits them; s then has no pages and is split
 * (never handed out again). */
static int release_fragment(span *s, size_t *released)
{
    size_t resident = resident_bytes(s->start, s->size);
    if (madvise(s->start, s->size, MADV_DONTNEED) != 0) return 0;
    *released += resident;
    s->paged = 0;
    s->split = 1;
    merge_free(s);
    return 1;
}

/* Before `fresh` bytes are faulted in: gives back paged free blocks until that many resident
 * bytes are gone (or none are left), so the RSS does not grow while freed pages sit idle.
 * First the fragments of FRAGMENT_MIN bytes and more, the smallest first: a block under a
 * huge page, or between two blocks in use, holds no whole huge page, and as long as a block in
 * use shares its huge pages the pages stay. Most such blocks fit no later request; kept, they
 * held 12 MB of the Phong chain with cmft's exponents at 256 when its output was made, where
 * its whole peak is ~50 MB (splitting their huge pages costs the ranges around them 4 KiB
 * pages). Then the blocks with
 * the most pages in memory inside their whole huge pages. A paged block found to hold no
 * pages at all becomes one of the blocks without pages. */
static void arena_release_for(size_t fresh)
{
    size_t released = 0;
    while (released < fresh) {
        span *least = NULL;
        for (span *s = arena.first; s; s = s->next) {
            char *from, *to;
            if (s->used || !s->paged) continue;
            whole_pages(s, &from, &to);
            int fragment = from == to && s->size >= FRAGMENT_MIN;
            if (fragment && (!least || s->size < least->size)) least = s;
        }
        if (!least || !release_fragment(least, &released)) break; /* (refused: keep the pages) */
    }
    while (released < fresh) {
        span *most = NULL;
        size_t most_bytes = 0;
        for (span *s = arena.first; s; s = s->next) {
            if (s->used || !s->paged) continue;
            char *from, *to;
            whole_pages(s, &from, &to);
            size_t bytes = resident_bytes(from, (size_t)(to - from));
            /* the whole block is read only when its huge pages hold nothing (its ends may) */
            if (bytes == 0 && resident_bytes(s->start, s->size) == 0) {
                s->paged = 0;
                s = merge_free(s); /* with its own kind only: never `most`, a paged block */
                continue;
            }
            if (bytes > most_bytes) most = s, most_bytes = bytes;
        }
        if (!most) break;
        size_t bytes = arena_release(most);
        if (!bytes) break; /* madvise refused or no memory for the records: keep the pages */
        released += bytes;
    }
}

/* The smallest free block of `paged` kind that holds size bytes, or NULL. */
static span *best_fit(size_t size, int paged)
{
    span *best = NULL;
    for (span *s = arena.first; s; s = s->next)
        if (!s->used && !s->split && s->paged == paged && s->size >= size && (!best || s->size < best->size))
            best = s;
    return best;
}

/* Hands out the first size bytes of free block b; the rest stays free, after it, same kind. */
static span *take_from(span *b, size_t size)
{
    span *rest = b->size - size >= ARENA_MIN ? malloc(sizeof *rest) : NULL;
    if (rest) {
        rest->start = b->start + size;
        rest->size = b->size - size;
        rest->paged = b->paged;
        rest->used = 0;
        rest->split = 0;
        link_after(b, rest);
        b->size = size;
    }
    b->used = 1;
    return b;
}

/* A block of `size` bytes (a multiple of ARENA_MIN) from the arena, or NULL: a paged free block
 * if one fits, otherwise a free block without pages or fresh address space from the arena's
 * top. As many resident bytes of other free blocks as it has bytes without pages are given
 * back first. */
static span *arena_take(size_t size)
{
    span *b = best_fit(size, 1);
    if (b) {
        b = take_from(b, size); /* in use now: not one of the blocks given back */
        size_t fresh = size - resident_bytes(b->start, size);
        if (fresh) arena_release_for(fresh);
        return b;
    }
    arena_release_for(size);
    b = best_fit(size, 0);
    if (b) return take_from(b, size);
    if ((size_t)(arena.end - arena.top) < size) return NULL;
    span *s = malloc(sizeof *s);
    if (!s) return NULL;
    s->start = arena.top;
    s->size = size;
    s->paged = 0;
    s->used = 1;
    s->split = 0;
    link_after(arena.last, s);
    arena.top += size;
    return s;
}

/* Frees the block starting at p (nothing when no block in use starts there). */
static void arena_give(char *p)
{
    span *s = arena.last; /* the latest blocks are the likeliest to go first */
    while (s && s->start != p) s = s->prev;
    if (!s || !s->used) return;
    s->used = 0;
    s->paged = resident_bytes(s->start, s->size) > 0; /* the pages its user wrote, if any */
    merge_free(s);
}

void *cli_arena_alloc(size_t bytes, void *user)
{
    (void)user;
    if (bytes > SIZE_MAX - ARENA_MIN) return NULL;
    if (bytes >= ARENA_MIN) {
        size_t size = (bytes + ARENA_MIN - 1) & ~(ARENA_MIN - 1);
        pthread_mutex_lock(&arena.lock);
        if (!arena.tried) arena.tried = 1, arena_reserve();
        span *s = arena.base ? arena_take(size) : NULL;
        char *start = s ? s->start : NULL;
        pthread_mutex_unlock(&arena.lock);
        if (start) return start;
    }
    void *p = NULL;
    if (posix_memalign(&p, 64, bytes ? bytes : 1) != 0) return NULL;
    return p;
}

void cli_arena_free(void *ptr, void *user)
{
    (void)user;
    if (!ptr) return;
    pthread_mutex_lock(&arena.lock);
    int ours = in_arena(ptr);
    if (ours) arena_give(ptr);
    pthread_mutex_unlock(&arena.lock);
    if (!ours) free(ptr);
}
