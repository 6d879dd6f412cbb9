"""Supervisors (L1 blocks): discrete-event mode machines (mode, guards, dwell timers, logged decisions)."""
