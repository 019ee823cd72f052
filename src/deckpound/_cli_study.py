"""CLI: comparison, studies, the paper job, benchmarks (registered as they are built)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    return None
