/* test_error.c -- gp_error: codes, messages, NULL tolerance. */
#include "gp_error.h"
#include "gp_test.h"

#include <string.h>

int main(void)
{
    gp_error e;
    gp_error_clear(&e);
    CHECK(e.code == GP_OK && e.message[0] == '\0');
    CHECK(gp_error_set(&e, GP_ERR_INVALID, "n = %d must be >= %d", 3, 16) == GP_ERR_INVALID);
    CHECK(e.code == GP_ERR_INVALID);
    CHECK(strcmp(e.message, "n = 3 must be >= 16") == 0);
    CHECK(gp_error_set(NULL, GP_ERR_NOMEM, "x") == GP_ERR_NOMEM);
    CHECK(strcmp(gp_status_name(GP_ERR_NOT_STAR), "not_star") == 0);
    /* a message longer than the buffer is truncated, not overflowed */
    char big[1000];
    memset(big, 'a', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    gp_error_set(&e, GP_ERR_INTERNAL, "%s", big);
    CHECK(strlen(e.message) == GP_ERROR_MESSAGE_MAX - 1);
    return gp_test_summary();
}
