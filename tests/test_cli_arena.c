/* The CLI's allocator (cli/arena.c): blocks are usable, aligned and disjoint; freed arena
 * blocks are reused best-fit, split and merged; a fresh block is handed out untouched; freed
 * memory goes back to the kernel, as many resident bytes as a request faults in fresh, the free
 * blocks that hold no whole huge page first; it is
 * safe from several threads. */
#define _DEFAULT_SOURCE /* mincore */
#include "test_support.h"

#include "arena.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

/* a byte every 4093 and the last one (when it is not one of those) */
static void fill(unsigned char *p, size_t n, unsigned seed)
{
    for (size_t i = 0; i < n; i += 4093) p[i] = (unsigned char)(seed + i / 4093);
    if ((n - 1) % 4093) p[n - 1] = (unsigned char)(seed ^ 0x5a);
}

static int intact(const unsigned char *p, size_t n, unsigned seed)
{
    for (size_t i = 0; i < n; i += 4093)
        if (p[i] != (unsigned char)(seed + i / 4093)) return 0;
    return (n - 1) % 4093 == 0 || p[n - 1] == (unsigned char)(seed ^ 0x5a);
}

/* Sizes across the small (malloc) and large (arena) paths keep their contents while others
 * come and go, and are 64-byte aligned. */
static void blocks_are_disjoint(void **state)
{
    (void)state;
    enum { N = 40 };
    static const size_t sizes[] = {1, 100, 4096, 65472, 65536, 70000, 1 << 20, 3u << 20, 9u << 20};
    unsigned char *p[N];
    size_t n[N];
    for (int i = 0; i < N; i++) {
        n[i] = sizes[i % 9];
        p[i] = cli_arena_alloc(n[i], NULL);
        assert_non_null(p[i]);
        assert_int_equal((uintptr_t)p[i] % 64, 0);
        fill(p[i], n[i], (unsigned)i);
    }
    for (int i = 0; i < N; i += 3) { /* free a third, allocate again, check everyone */
        cli_arena_free(p[i], NULL);
        p[i] = cli_arena_alloc(n[i], NULL);
        assert_non_null(p[i]);
        fill(p[i], n[i], (unsigned)i);
    }
    for (int i = 0; i < N; i++) assert_true(intact(p[i], n[i], (unsigned)i));
    for (int i = 0; i < N; i++) cli_arena_free(p[i], NULL);
    cli_arena_free(NULL, NULL);
}

/* Best fit, split and merge (AddressSanitizer builds keep every block in malloc, where
 * addresses say nothing). */
static void freed_blocks_are_reused(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    const size_t MB = (size_t)1 << 20;
    unsigned char *a = cli_arena_alloc(8 * MB, NULL), *b = cli_arena_alloc(8 * MB, NULL);
    assert_non_null(a);
    assert_non_null(b);
    cli_arena_free(a, NULL);
    unsigned char *c = cli_arena_alloc(3 * MB, NULL); /* the freed block, split */
    unsigned char *d = cli_arena_alloc(3 * MB, NULL); /* its rest */
    assert_ptr_equal(c, a);
    assert_true(d > c && d < a + 8 * MB);
    cli_arena_free(c, NULL);
    cli_arena_free(d, NULL);
    unsigned char *e = cli_arena_alloc(8 * MB, NULL); /* the pieces merged again */
    assert_ptr_equal(e, a);
    fill(e, 8 * MB, 7);
    fill(b, 8 * MB, 9);
    assert_true(intact(e, 8 * MB, 7));
    cli_arena_free(e, NULL);
    cli_arena_free(b, NULL);
#endif
}

#if !defined(__SANITIZE_ADDRESS__)
/* Bytes of [p, p + n) whose pages are in memory (mincore), whole pages inside the range. */
static size_t resident_bytes(const unsigned char *p, size_t n)
{
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    uintptr_t from = ((uintptr_t)p + page - 1) & ~(uintptr_t)(page - 1);
    uintptr_t to = ((uintptr_t)p + n) & ~(uintptr_t)(page - 1);
    if (to <= from) return 0;
    size_t pages = (to - from) / page;
    unsigned char *vec = malloc(pages);
    assert_non_null(vec);
    assert_int_equal(mincore((void *)from, to - from, vec), 0);
    size_t count = 0;
    for (size_t i = 0; i < pages; i++) count += vec[i] & 1;
    free(vec);
    return count * page;
}
#endif

/* Freed blocks keep their pages for reuse; only a request that fits none of them and takes
 * fresh memory makes the free blocks with the most pages go back to the kernel, as many bytes
 * as it takes, so the resident memory never holds idle freed pages beside fresh ones. */
static void freed_memory_goes_back(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    const size_t MB = (size_t)1 << 20, big = 96 * MB;
    enum { N = 5 };
    unsigned char *block[N], *fence[N];
    for (int i = 0; i < N; i++) {
        block[i] = cli_arena_alloc(big, NULL);
        /* keeps the freed blocks from merging; larger than the 40 MiB the tests before freed,
         * so that it follows its block */
        fence[i] = cli_arena_alloc(48 * MB, NULL);
        assert_non_null(block[i]);
        assert_non_null(fence[i]);
        memset(block[i], 1 + i, big);
    }
    /* five freed 96 MiB blocks keep their pages, and one is reused with them */
    for (int i = 0; i < N; i++) cli_arena_free(block[i], NULL);
    size_t kept = 0;
    for (int i = 0; i < N; i++) kept += resident_bytes(block[i], big);
    assert_true(kept >= N * (big - 2 * MB));
    unsigned char *again = cli_arena_alloc(big, NULL);
    assert_true(again == block[0] || again == block[1] || again == block[2] || again == block[3] ||
                again == block[4]);
    assert_true(resident_bytes(again, big) >= big - 2 * MB);
    cli_arena_free(again, NULL);
    /* 200 MiB fit no free block: at least that much of them goes back first (three blocks of
     * the five, the largest resident first), and the fresh block has no pages yet */
    const size_t large = 200 * MB;
    unsigned char *fresh = cli_arena_alloc(large, NULL);
    assert_non_null(fresh);
    assert_int_equal(resident_bytes(fresh, large), 0);
    kept = 0;
    for (int i = 0; i < N; i++) kept += resident_bytes(block[i], big);
    assert_true(kept <= (size_t)(N - 3) * big);
    assert_true(kept >= (size_t)(N - 3) * (big - 2 * MB));
    /* a dropped block is usable again: its pages come back zeroed, not with the old bytes */
    unsigned char *reused = NULL;
    for (int i = 0; i < N && !reused; i++)
        if (resident_bytes(block[i], big) == 0) reused = block[i];
    assert_non_null(reused);
    unsigned char *got = cli_arena_alloc(big, NULL);
    assert_non_null(got);
    /* best fit may hand out any free 96 MiB block: a dropped one reads zero */
    if (resident_bytes(got, big) == 0) assert_true(got[big / 2] == 0 && got[big - 1] == 0);
    memset(got, 9, big);
    assert_true(got[big / 2] == 9 && got[big - 1] == 9);
    cli_arena_free(got, NULL);
    cli_arena_free(fresh, NULL);
    for (int i = 0; i < N; i++) cli_arena_free(fence[i], NULL);
#endif
}

/* The allocator keeps what it knows of a block beside it, never in it: a fresh block has no
 * page in memory when it is handed out, so each page is first touched (faulted in, cleared
 * by the kernel) by whichever thread writes its data, not by the allocating one. */
static void fresh_blocks_are_untouched(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    const size_t MB = (size_t)1 << 20, n = 24 * MB; /* larger than the 16 MiB freed before */
    unsigned char *p = cli_arena_alloc(n, NULL);
    assert_non_null(p);
    assert_int_equal(resident_bytes(p, n), 0);
    p[n / 2] = 1; /* one write faults in its own page (2 MiB at most), not the block's first */
    assert_int_equal(resident_bytes(p, 4096), 0);
    assert_true(resident_bytes(p, n) > 0 && resident_bytes(p, n) <= 2 * MB);
    cli_arena_free(p, NULL);
#endif
}

/* A freed block gives back only the whole 2 MiB pages inside it: the pages at its ends that
 * share a 2 MiB page with a block in use stay (dropping part of a huge page splits it, and the
 * range then faults 4 KiB at a time), as fragments: fragments_go_first has what becomes of
 * them at the next request that faults fresh pages. 2 MiB is the arena's alignment and the huge page size
 * on x86-64; with 4 KiB pages only, the same bytes stay and go. */
static void release_keeps_shared_huge_pages(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    const size_t MB = (size_t)1 << 20, huge = 2 * MB, KB64 = (size_t)64 << 10;
    /* a block whose start and end fall inside 2 MiB pages shared with its used neighbours:
     * after a 1 MiB + 64 KiB neighbour, whatever the arena's top was, one of the two ends is
     * off a 2 MiB boundary; 9 MiB + 64 KiB holds at least three whole 2 MiB pages */
    unsigned char *before = cli_arena_alloc(MB + KB64, NULL);
    unsigned char *x = cli_arena_alloc(9 * MB + KB64, NULL);
    unsigned char *after = cli_arena_alloc(MB, NULL);
    assert_non_null(before);
    assert_non_null(x);
    assert_non_null(after);
    size_t n = 9 * MB + KB64;
    memset(before, 1, MB + KB64);
    memset(x, 2, n);
    memset(after, 3, MB);
    unsigned char *from = (unsigned char *)(((uintptr_t)x + huge - 1) & ~(uintptr_t)(huge - 1));
    unsigned char *to = (unsigned char *)(((uintptr_t)x + n) & ~(uintptr_t)(huge - 1));
    assert_true(to - from >= (ptrdiff_t)(3 * huge));
    assert_true(from > x || to < x + n);
    cli_arena_free(x, NULL);
    /* a request larger than every free block: the free blocks' whole 2 MiB pages go back */
    const size_t large = (size_t)2 << 30;
    unsigned char *fresh = cli_arena_alloc(large, NULL);
    assert_non_null(fresh);
    assert_int_equal(resident_bytes(from, (size_t)(to - from)), 0);
    assert_int_equal(resident_bytes(x, (size_t)(from - x)), (size_t)(from - x));
    assert_int_equal(resident_bytes(to, (size_t)(x + n - to)), (size_t)(x + n - to));
    /* the kept ends are paged free blocks: a request they fit reuses one, with its bytes */
    size_t head = (size_t)(from - x), tail = (size_t)(x + n - to);
    if (head >= KB64) {
        unsigned char *again = cli_arena_alloc(head, NULL);
        assert_ptr_equal(again, x);
        assert_true(again[0] == 2 && again[head - 1] == 2);
        cli_arena_free(again, NULL);
    } else {
        assert_true(tail >= KB64);
    }
    cli_arena_free(fresh, NULL);
    cli_arena_free(before, NULL);
    cli_arena_free(after, NULL);
#endif
}

/* A freed block holds the pages its user wrote, which may be few of its bytes: a request that
 * takes such a block faults the rest in fresh, so as many resident bytes of other free blocks
 * go back first (counting the partly written block whole kept them, and the RSS grew). Run in
 * a child process, on an arena of its own whose layout is known: one used block apart, the
 * two free blocks cannot merge. */
#if !defined(__SANITIZE_ADDRESS__)
/* Runs check in a child process (an arena of its own, untouched): it must return 0. */
static void in_child(int (*check)(void))
{
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) _exit(check());
    int status = 0;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
}

static int partly_written_child(void)
{
    const size_t MB = (size_t)1 << 20;
    unsigned char *dense = cli_arena_alloc(16 * MB, NULL);
    unsigned char *fence = cli_arena_alloc(2 * MB, NULL);
    unsigned char *sparse = cli_arena_alloc(64 * MB, NULL);
    if (!dense || !fence || !sparse) return 1;
    memset(dense, 2, 16 * MB);
    memset(sparse, 1, 4 * MB); /* a buffer sized for the worst case, 4 MiB of it written */
    cli_arena_free(dense, NULL);
    cli_arena_free(sparse, NULL);
    if (resident_bytes(dense, 16 * MB) != 16 * MB) return 2;
    /* only the sparse block fits: 44 MiB of the 48 are fresh, so the dense block goes back */
    unsigned char *big = cli_arena_alloc(48 * MB, NULL);
    if (big != sparse) return 3;
    if (resident_bytes(dense, 16 * MB) != 0) return 4;
    if (resident_bytes(big, 4 * MB) != 4 * MB || big[4 * MB - 1] != 1) return 5; /* kept */
    return 0;
}
#endif

static void partly_written_blocks_count_their_pages(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    in_child(partly_written_child);
#endif
}

/* A free block that holds no whole 2 MiB page (a fragment: here 1 MiB between two blocks in
 * use, which keep the huge pages it is on) goes back before the whole pages of larger free
 * blocks, and its range is never handed out again (its huge pages are split; fresh address
 * space faults 2 MiB at once). In a child process, on an arena of its own. */
#if !defined(__SANITIZE_ADDRESS__)
static int fragment_child(void)
{
    const size_t MB = (size_t)1 << 20;
    unsigned char *a = cli_arena_alloc(MB, NULL), *fragment = cli_arena_alloc(MB, NULL);
    unsigned char *b = cli_arena_alloc(MB, NULL), *large = cli_arena_alloc(8 * MB, NULL);
    unsigned char *c = cli_arena_alloc(MB, NULL);
    if (!a || !fragment || !b || !large || !c) return 1;
    memset(a, 1, MB), memset(fragment, 2, MB), memset(b, 3, MB), memset(large, 4, 8 * MB), memset(c, 5, MB);
    cli_arena_free(fragment, NULL);
    cli_arena_free(large, NULL);
    if (resident_bytes(fragment, MB) != MB) return 2;
    /* 1 MiB more than the large block: fresh, so 9 MiB go back, the fragment first */
    unsigned char *fresh = cli_arena_alloc(9 * MB, NULL);
    if (!fresh || fresh == large) return 3;
    if (resident_bytes(fragment, MB) != 0) return 4;
    if (resident_bytes(a, MB) != MB || resident_bytes(b, MB) != MB || a[MB - 1] != 1 || b[0] != 3) return 5;
    /* a request the fragment fits gets other memory */
    unsigned char *again = cli_arena_alloc(MB, NULL);
    if (!again || again == fragment) return 6;
    return 0;
}
#endif

static void fragments_go_first(void **state)
{
    (void)state;
#if defined(__SANITIZE_ADDRESS__)
    skip();
#else
    in_child(fragment_child);
#endif
}

static void *churn(void *arg)
{
    unsigned seed = (unsigned)(uintptr_t)arg;
    unsigned char *held[8] = {0};
    size_t size[8] = {0};
    for (int i = 0; i < 400; i++) {
        int k = i % 8;
        if (held[k]) {
            if (!intact(held[k], size[k], seed + (unsigned)k)) return (void *)1;
            cli_arena_free(held[k], NULL);
        }
        size[k] = (size_t)(64 + (seed * 7919u + (unsigned)i * 104729u) % (3u << 20));
        held[k] = cli_arena_alloc(size[k], NULL);
        if (!held[k]) return (void *)1;
        fill(held[k], size[k], seed + (unsigned)k);
    }
    for (int k = 0; k < 8; k++) cli_arena_free(held[k], NULL);
    return NULL;
}

static void threads_share_it(void **state)
{
    (void)state;
    pthread_t t[4];
    for (int i = 0; i < 4; i++) assert_int_equal(pthread_create(&t[i], NULL, churn, (void *)(uintptr_t)(i + 1)), 0);
    for (int i = 0; i < 4; i++) {
        void *r = NULL;
        pthread_join(t[i], &r);
        assert_null(r);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        /* first: its child process starts from the arena untouched */
        cmocka_unit_test(partly_written_blocks_count_their_pages),
        cmocka_unit_test(fragments_go_first), /* (a child process too) */
        /* first in this process: on a fresh arena, addresses are known */
        cmocka_unit_test(freed_blocks_are_reused),
        cmocka_unit_test(fresh_blocks_are_untouched),
        cmocka_unit_test(freed_memory_goes_back), /* after those two only: 40 MiB freed so far */
        cmocka_unit_test(release_keeps_shared_huge_pages),
        cmocka_unit_test(blocks_are_disjoint),
        cmocka_unit_test(threads_share_it),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
