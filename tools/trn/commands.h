/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/commands.h - prototypes of the subcommands in commands.def. */
#ifndef TRN_TOOLS_COMMANDS_H
#define TRN_TOOLS_COMMANDS_H

#define TRN_COMMAND(sym, name, summary) int trn_cmd_##sym(int argc, char **argv);
#include "commands.def"
#undef TRN_COMMAND

#endif
