"""Pilot models and their loops: forcing functions, pilot models, closed loops, adaptation.

``forcing`` (sums of sines), ``model`` (Chapter 2's multi-channel pilot), ``loop`` (the roll
loop), ``pitch`` and ``pitch_loop`` (Chapter 6's pitch task flown through a configuration),
``adapt`` (a pilot that tunes itself to the motion system), ``lead`` (lead from the vestibular
sensors) and ``records`` (the ``twin-pilot/1`` run format).
"""
