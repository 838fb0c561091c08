"""Pilots in the loop (thesis Ch 2, 6, 7): tasks, pilot models, closed loops, identification."""
