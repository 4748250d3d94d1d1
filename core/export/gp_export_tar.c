/* gp_export_tar.c -- POSIX ustar members in the staging buffer, for the formats that are a tar
 * (lammps-relax, a fv3d pack's lammps): one writer, so that both archives carry the same
 * header fields and the same padding. */
#include "gp_export_internal.h"

#include <stdio.h>
#include <string.h>

/* The header block of a member. Owner, group and time are 0: the same job gives the same bytes
 * at every download. */
static void tar_header(unsigned char h[GP_XW_TAR_BLOCK], const char *name, char type,
                       uint64_t size)
{
    memset(h, 0, GP_XW_TAR_BLOCK);
    snprintf((char *)h, 100, "%s", name);
    memcpy(h + 100, type == '5' ? "0000755" : "0000644", 8);
    memcpy(h + 108, "0000000", 8);
    memcpy(h + 116, "0000000", 8);
    snprintf((char *)h + 124, 12, "%011llo", (unsigned long long)size);
    memcpy(h + 136, "00000000000", 12);
    memset(h + 148, ' ', 8); /* the checksum counts its own field as spaces */
    h[156] = (unsigned char)type;
    memcpy(h + 257, "ustar", 6);
    memcpy(h + 263, "00", 2);
    unsigned sum = 0;
    for (int k = 0; k < GP_XW_TAR_BLOCK; k++) sum += h[k];
    snprintf((char *)h + 148, 7, "%06o", sum & 0777777u);
    h[155] = ' ';
}

int gp_xw_tar_header(gp_export *e, const char *name, char type, uint64_t size)
{
    unsigned char h[GP_XW_TAR_BLOCK];
    tar_header(h, name, type, size);
    return gp_xw_bytes(e, h, GP_XW_TAR_BLOCK);
}

int gp_xw_tar_file(gp_export *e, const char *name, int (*write)(gp_export *e))
{
    if (gp_xw_bytes(e, NULL, GP_XW_TAR_BLOCK)) return -1; /* the header's place */
    size_t start = e->len;
    if (write(e)) return -1;
    uint64_t n = e->len - start;
    unsigned char h[GP_XW_TAR_BLOCK];
    tar_header(h, name, '0', n);
    memcpy(e->buf + start - GP_XW_TAR_BLOCK, h, GP_XW_TAR_BLOCK);
    return gp_xw_tar_pad(e, n);
}

int gp_xw_tar_pad(gp_export *e, uint64_t size)
{
    size_t r = (size_t)(size % GP_XW_TAR_BLOCK);
    return r ? gp_xw_bytes(e, NULL, GP_XW_TAR_BLOCK - r) : 0;
}

int gp_xw_tar_end(gp_export *e)
{
    return gp_xw_bytes(e, NULL, 2 * GP_XW_TAR_BLOCK);
}
