"""The tutor's caps on sizes and counts, in one place.

Everything the tutor reads from a person or a folder is bounded by one of these numbers,
so that no file, zip or class folder can keep it busy for minutes or fill its memory.
Going over a cap raises :class:`~tutor.errors.LimitError` (or, in the class analysis,
lists the file as not counted) with the cap and what to do. Each cap is far above what
the tutor itself writes or a person makes by hand; the README's "Limits" table states
them. The module imports nothing, so every layer may use it.
"""

__all__ = [
    "MAX_FILE_BYTES",
    "MAX_RUN_FILE_BYTES",
    "MAX_UPLOAD_BYTES",
    "MAX_CLASS_FILES",
    "MAX_ZIP_MEMBERS",
    "MAX_ZIP_BYTES",
    "MAX_ZIP_RATIO",
    "ZIP_RATIO_FROM_BYTES",
    "MAX_DEMOS_PER_RUN",
    "MAX_SAMPLES_PER_DEMO",
    "MAX_SAMPLES_PER_FILE",
    "MAX_TEACHERS",
    "MAX_SEEDS",
    "MAX_SEED",
    "MAX_STROKE_POINTS",
    "MAX_RECORDING_SECONDS",
    "MAX_RECORDING_SAMPLES",
    "MAX_TEXT_CHARS",
]

MB = 1024 * 1024

#: any file the tutor reads (a run, a demonstration file, a plan): larger ones are refused
#: unread
MAX_FILE_BYTES = 50 * MB
#: one run file in a class folder or zip: a run of MAX_DEMOS_PER_RUN pick-and-place
#: demonstrations is about 2 MB
MAX_RUN_FILE_BYTES = 5 * MB
#: one file uploaded with a tutor's Load button (it travels through the browser)
MAX_UPLOAD_BYTES = 10 * MB

#: run files (``.json``, also inside zips) in one class folder or zip: 200 trainees with
#: 4 runs each, every run saved twice, make 1600
MAX_CLASS_FILES = 2000
#: entries (files and folders) in one zip, counted before it is unpacked
MAX_ZIP_MEMBERS = 5000
#: what all of one zip's entries unpack to, together
MAX_ZIP_BYTES = 500 * MB
#: a zip entry may unpack to at most this many times its packed size (run files pack
#: about 3 times); more is what a "zip bomb" does ...
MAX_ZIP_RATIO = 100
#: ... when it unpacks to more than this (small files may pack better harmlessly)
ZIP_RATIO_FROM_BYTES = 1 * MB

#: demonstrations in one run, and in one demonstration file: a simulated teacher gives at
#: most 20 (its patience); replaying 100 pick-and-place demonstrations takes about half a
#: minute
MAX_DEMOS_PER_RUN = 100
#: samples (rows) in one demonstration of a demonstration file: 5 s recorded at 1 kHz
#: (the tutor resamples every demonstration to 200)
MAX_SAMPLES_PER_DEMO = 5000
#: samples (rows) in one demonstration file, all demonstrations together (about 2 s to read)
MAX_SAMPLES_PER_FILE = 100_000

#: the largest cohort simulated: 100 times the paper's Experiment 1 (about a quarter of an
#: hour per core for Experiment 1, more for Experiment 2); larger requests are refused
#: before any work rather than left running for days
MAX_TEACHERS = 3000
#: the most seeds one robustness run or adaptive study goes over (each seed is a whole
#: cohort: 1000 of the paper's Experiment 1 take about a day on two cores)
MAX_SEEDS = 1000
#: the largest seed: it must fit the 64-bit integers of the result tables
MAX_SEED = 2**63 - 1
#: the most points one stroke may have (about 3 minutes of drawing at 120 pointer
#: events a second; a keyboard stroke has one point per millimetre of its path)
MAX_STROKE_POINTS = 20_000
#: the longest recording of a trainee's own hand guiding the arm (s): a careful
#: demonstration takes 10 to 40 s, and a run's clock has 15 minutes in all
MAX_RECORDING_SECONDS = 300.0
#: the most samples one such recording may have: 5 minutes at 120 samples a second
MAX_RECORDING_SAMPLES = 36_000
#: the longest text a field may send (a file path may be 4096 bytes long)
MAX_TEXT_CHARS = 4096
