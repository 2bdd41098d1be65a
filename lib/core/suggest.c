/* "Did you mean": the name nearest to a mistyped word, for the job parser's unknown keys and enum
 * values and the command line's unknown commands, options and names. One measure everywhere, so
 * a typo is caught the same way in a job file and on the command line. */
#include "core/core.h"

#include <string.h>

#define MAX_LEN 64 /* longer words are never compared */

static unsigned char lower(char c)
{
    return c >= 'A' && c <= 'Z' ? (unsigned char)(c - 'A' + 'a') : (unsigned char)c;
}

static size_t min2(size_t a, size_t b)
{
    return a < b ? a : b;
}

size_t rb_edit_distance(const char *a, size_t la, const char *b, size_t lb)
{
    /* Optimal string alignment: Levenshtein's three edits plus a swap of neighbours, each 1
     * (Damerau), over three rows of the table. */
    size_t rows[3][MAX_LEN + 1];
    if (la > MAX_LEN || lb > MAX_LEN)
        return SIZE_MAX;
    size_t *back = rows[0], *prev = rows[1], *cur = rows[2];
    for (size_t j = 0; j <= lb; j++)
        prev[j] = j;
    for (size_t i = 1; i <= la; i++) {
        cur[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t d = prev[j - 1] + (lower(a[i - 1]) != lower(b[j - 1]));
            d = min2(d, prev[j] + 1);
            d = min2(d, cur[j - 1] + 1);
            if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
                lower(a[i - 2]) == lower(b[j - 1]))
                d = min2(d, back[j - 2] + 1);
            cur[j] = d;
        }
        size_t *t = back;
        back = prev, prev = cur, cur = t;
    }
    return prev[lb];
}

void rb_suggest_init(struct rb_suggest *s, const char *word)
{
    *s = (struct rb_suggest){.word = word, .distance = SIZE_MAX};
}

void rb_suggest_offer(struct rb_suggest *s, const char *name, size_t len)
{
    size_t word_len = strlen(s->word);
    if (len >= sizeof(s->best))
        return;
    size_t d = rb_edit_distance(s->word, word_len, name, len);
    /* Two edits at most, and no more than a third of the longer: "bpdt" is 'bdpt', "set" is
     * not 'out'. */
    if (d > 2 || 3 * d > (word_len > len ? word_len : len) || d >= s->distance)
        return;
    s->distance = d;
    memcpy(s->best, name, len);
    s->best[len] = '\0';
}
