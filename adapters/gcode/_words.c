/* The G-code lexer's plain path (adapters/gcode/lexer.py, tokenize) in one pass over the
 * plain text: its words (letter, line, where the number is) and their numbers.
 *
 * A plain C library (no Python API), built by `pip install` where a C compiler is found
 * (pyproject.toml: an optional extension), loaded with ctypes by adapters/gcode/lexer.py
 * through core/model/native.py; where it is absent numpy's code runs. The results are
 * those of numpy's code bit for bit (tests/test_native.py): a number of at most
 * MAX_DIGITS digits is m / 10^k with m its digits' integer (below 2^53) and k its digits
 * after the dot, both exact doubles, one correctly rounded division -- what
 * adapters/gcode/numbers.py computes eight bytes at a time; a longer one is left to
 * Python's float, as there.
 *
 * The plain text holds upper-case letters, the number bytes 0-9 . + - and one newline per
 * line, and ends with a newline. A word is a letter and the bytes up to the next letter or
 * newline. A line is bad -- the per-line tokeniser reads it -- where a word has no number
 * ("empty"), a number is not [+-]digits[.digits] or [+-].digits, or number bytes come
 * before the line's first letter.
 */

#include <stdint.h>

#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif

/* The digits a number read here may have (adapters/gcode/numbers.py MAX_DIGITS). */
#define MAX_DIGITS 15

/* Word kinds. */
#define READ 0     /* its number read into value */
#define EMPTY 1    /* a letter with no number */
#define BAD 2      /* a number that is not well formed */
#define LONG 3     /* well formed, more than MAX_DIGITS digits: Python's float reads it */

static const double POW10[MAX_DIGITS + 1] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                             1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};

static inline int is_break(uint8_t ch) { return (ch >= 'A' && ch <= 'Z') || ch == '\n'; }

EXPORT int64_t ncperf_words_version(void) { return 1; }

/* The number of letters in the text (the words' count). */
EXPORT int64_t gcode_letters(const uint8_t *c, int64_t size) {
    int64_t count = 0;
    for (int64_t i = 0; i < size; i++) count += c[i] >= 'A' && c[i] <= 'Z';
    return count;
}

/* Every word of the text c[0..size) (which ends with a newline): its line (newlines
   before it), letter, place, the end of its number (the next break), its number (value,
   where kind is READ) and kind; bad_line[line] = 1 on the bad lines (n_lines entries:
   the text's newlines). Returns the words' count. */
EXPORT int64_t gcode_words(const uint8_t *c, int64_t size, int64_t *wline, uint8_t *letter,
                           int64_t *lpos, int64_t *span_end, double *value, uint8_t *kind,
                           uint8_t *bad_line) {
    int64_t line = 0, w = 0, i = 0;
    if (size && !is_break(c[0])) bad_line[0] = 1; /* numbers before the first letter */
    while (i < size) {
        uint8_t ch = c[i];
        if (ch == '\n') {
            line++;
            i++;
            if (i < size && !is_break(c[i])) bad_line[line] = 1;
            continue;
        }
        if (!(ch >= 'A' && ch <= 'Z')) { /* (number bytes before a line's first letter) */
            i++;
            continue;
        }
        int64_t s = i + 1, e = s;
        while (e < size && !is_break(c[e])) e++;
        wline[w] = line;
        letter[w] = ch;
        lpos[w] = i;
        span_end[w] = e;
        value[w] = 0.0;
        uint8_t k = READ;
        if (e == s) {
            k = EMPTY;
        } else {
            int64_t p = s;
            int neg = 0;
            if (c[p] == '+' || c[p] == '-') {
                neg = c[p] == '-';
                p++;
            }
            int64_t digits = 0, after = 0;
            uint64_t m = 0;
            int dot = 0, ok = 1;
            for (; p < e; p++) {
                uint8_t d = c[p];
                if (d >= '0' && d <= '9') {
                    digits++;
                    if (digits <= MAX_DIGITS) m = m * 10 + (uint64_t)(d - '0');
                    after += dot;
                } else if (d == '.' && !dot) {
                    dot = 1;
                } else {
                    ok = 0; /* a second dot, a sign inside, anything else */
                }
            }
            if (!ok || digits == 0) {
                k = BAD;
            } else if (digits > MAX_DIGITS) {
                k = LONG;
            } else {
                double v = (double)m / POW10[after];
                value[w] = neg ? -v : v;
            }
        }
        kind[w] = k;
        if (k == EMPTY || k == BAD) bad_line[line] = 1;
        w++;
        i = e;
    }
    return w;
}

/* Windows' linker wants the entry point of a Python extension, which setuptools builds
   this library as; nothing imports it (ctypes loads it). */
#if defined(_WIN32)
EXPORT void *PyInit__words(void) { return 0; }
#endif
