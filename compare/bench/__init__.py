"""Measurements a user can rerun (``deckpound bench``, ``deckpound stress``): speed, work against
precision, what each work-saving skip saves, numerical stability and peak memory."""
