"""Answers the trigger frame's decode with a line that is not JSON."""

from reference import serve

serve(lambda reply: "Segmentation fault? no: just garbage on stdout")
