/* page.h -- the dashboard page as GET / serves it: dashboard.html (compiled into dashboard.c)
 * with what it shows of the kinds filled in (kind.h: gpd_kinds_json -- their example specs,
 * views and export formats, so that the page names none itself), and its
 * Content-Security-Policy: the SHA-256 of each inline script, style and style="" attribute of
 * the page as served, and nothing from elsewhere. Built once, on the first call; thread-safe. */
#ifndef GPD_PAGE_H
#define GPD_PAGE_H

/* Builds the page and its policy: 0, or -1 on out of memory. */
int gpd_page_init(void);
/* The page (NUL-terminated), or NULL when it could not be built. */
const char *gpd_page_html(void);
/* Its Content-Security-Policy, or NULL when the page could not be built. */
const char *gpd_page_csp(void);

#endif /* GPD_PAGE_H */
