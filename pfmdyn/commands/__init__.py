"""One thin module per ``pfmdyn`` subcommand: argparse, call the library, print/write."""
