"""The one run loop (:mod:`.loop`) and its observers (:mod:`.observers`)."""
